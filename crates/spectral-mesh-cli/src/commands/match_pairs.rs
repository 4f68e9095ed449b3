//! `spectral-mesh match-pairs INPUTS... --out DIR [--pairs all|consecutive|FILE]`: the
//! `match` pipeline on pairs of a collection (the library's `batch::pairs`: the pairs, the
//! job of one pair, the map files and `pairs.csv`). Pairs run one after the other in this
//! process, each on every core; a bad mesh gives a failed row naming the file, and the
//! batch goes on.

use std::path::PathBuf;

use anyhow::{Result, bail};
use spectral_mesh::batch::pairs::{DEFAULT_PAIR_GEODESIC_SOURCES, parse_pair_list};
use spectral_mesh::batch::{
    PairParams, Pairing, SolveParams, Status, plan_pairs, prepare_output, process_pair,
    remove_stale_temporaries, resolve_inputs, write_pairs_summary,
};
use spectral_mesh::cancel::CancelToken;
use spectral_mesh::defaults::laplacian_for;

use super::matching::MatchFlags;

/// Arguments of `match-pairs`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Inputs: mesh files, folders, glob patterns or @FILE manifests (as for `batch`).
    #[arg(required = true)]
    pub inputs: Vec<String>,
    /// Output folder: maps/SOURCE--TARGET.txt per pair and pairs.csv.
    #[arg(long, short = 'o')]
    pub out: PathBuf,
    /// Which pairs: all (every unordered pair, the earlier input the source),
    /// consecutive, or a file of lines `SOURCE TARGET [TRUTH]` (names, paths or
    /// positions from 0; TRUTH a true map, relative to the file). Default: all.
    #[arg(long)]
    pub pairs: Option<String>,
    #[command(flatten)]
    pub flags: MatchFlags,
    /// Most geodesic solves of the evaluation of one pair against its true map.
    #[arg(long, default_value_t = DEFAULT_PAIR_GEODESIC_SOURCES)]
    pub geodesic_sources: usize,
    /// Write into a folder that holds other files (not made by a batch).
    #[arg(long, short = 'f')]
    pub force: bool,
}

fn pairing(spec: Option<&str>) -> Result<Pairing> {
    let Some(spec) = spec else {
        return Ok(Pairing::default());
    };
    if let Ok(p) = spec.parse() {
        return Ok(p);
    }
    let path = PathBuf::from(spec);
    let text = std::fs::read_to_string(&path).map_err(|e| {
        anyhow::anyhow!(
            "--pairs {spec}: not all or consecutive, and cannot read it as a pair list: {e}"
        )
    })?;
    let base = path.parent().map(PathBuf::from).unwrap_or_default();
    Ok(Pairing::List(parse_pair_list(&text, spec, &base)?))
}

/// Matches the pairs and writes their maps and the summary.
pub fn run(args: Args) -> Result<()> {
    let params = PairParams {
        matching: args.flags.params()?,
        solve: SolveParams {
            laplacian: laplacian_for(args.flags.laplacian, false)?,
            normalize: !args.flags.no_normalize,
            ..SolveParams::default()
        },
        max_geodesic_sources: Some(args.geodesic_sources),
    };
    params.validate()?;
    let inputs = resolve_inputs(&args.inputs)?;
    let jobs = plan_pairs(&inputs, &pairing(args.pairs.as_deref())?)?;
    prepare_output(&args.out, args.force)?;
    remove_stale_temporaries(&args.out);
    let t0 = std::time::Instant::now();
    let mut records = Vec::with_capacity(jobs.len());
    for (i, job) in jobs.iter().enumerate() {
        let rec = process_pair(job, &params, &args.out, &CancelToken::new());
        let what = match (&rec.error, rec.mean_geodesic_error) {
            (Some(e), _) => format!("failed: {e}"),
            (None, Some(err)) => format!(
                "{:.2} s, mean geodesic error {err:.3e}",
                rec.timings.seconds
            ),
            (None, None) => format!("{:.2} s", rec.timings.seconds),
        };
        eprintln!("[{}/{}] {}: {what}", i + 1, jobs.len(), job.name);
        records.push(rec);
    }
    let csv = write_pairs_summary(&args.out, &records)?;
    let failed: Vec<_> = records
        .iter()
        .filter(|r| r.status == Status::Failed)
        .collect();
    println!(
        "{} pairs in {:.1} s: {} matched, {} failed; summary -> {}",
        records.len(),
        t0.elapsed().as_secs_f64(),
        records.len() - failed.len(),
        failed.len(),
        csv.display()
    );
    if !failed.is_empty() {
        bail!(
            "{} of {} pairs failed (listed above and in {})",
            failed.len(),
            records.len(),
            csv.display()
        );
    }
    Ok(())
}
