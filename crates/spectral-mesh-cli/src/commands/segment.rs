//! `spectral-mesh segment MESH --signature hks:t=0.1 --persistence 0.05 -o labels.txt`:
//! patches = watershed basins of the maxima of a signature, with persistence merging.

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use spectral_mesh::fields::segmentation::{SegmentParams, segment};
use spectral_mesh::spectral::distances::spectral_function;
use spectral_mesh::spectral::filters::Filter;
use spectral_mesh::spectral::signatures::{auto_diffusion, hks, wks};
use spectral_mesh_render::colormap::hsv_to_rgb;

use super::eigs::{BasisArgs, FIGURE_EXTS, check_outputs, extension, normalized};
use crate::figure::{Figure, FigureArgs, read_field};
use crate::input;
use crate::output::write_atomic;

/// Help of `--signature`.
const SIGNATURE_HELP: &str = "The field whose maxima seed the patches:
  hks:t=0.1                  heat kernel signature at time t (default)
  adf:t=0.1                  auto-diffusion function
  wks:e=2.0,sigma=0.5        wave kernel signature at energy e (log-eigenvalue)
  biharmonic-function        G(p,p) of the bi-harmonic filter (also commute-function)
  spectral-function:FILTER   G(p,p) of any filter (see `distance --help`)
  field:FILE                 a per-vertex field, one value per line (no eigenpairs needed)
Times are for the shape scaled to unit area unless --no-normalize.";

/// Arguments of `segment`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file or built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// The field to segment (see below).
    #[arg(long, default_value = "hks:t=0.1", long_help = SIGNATURE_HELP)]
    pub signature: String,
    /// Merge threshold relative to the field's range: basins whose maximum rises less
    /// than this above their saddle join their elder neighbour.
    #[arg(long, default_value_t = 0.05)]
    pub persistence: f64,
    #[command(flatten)]
    pub basis: BasisArgs,
    /// Use the basis as given instead of the shape scaled to unit area.
    #[arg(long)]
    pub no_normalize: bool,
    /// Output file(s): .txt (labels, one per line), or .png, .wrl, .ply (patches in
    /// distinct colours), repeatable.
    #[arg(long, short = 'o', required = true)]
    pub out: Vec<PathBuf>,
    /// Also write the segmented field, one value per line.
    #[arg(long)]
    pub field_out: Option<PathBuf>,
    /// Overwrite existing outputs.
    #[arg(long, short = 'f')]
    pub force: bool,
    #[command(flatten)]
    pub figure: FigureArgs,
}

/// A parsed `--signature`.
#[derive(Debug, Clone, PartialEq)]
enum Source {
    Hks(f64),
    Adf(f64),
    Wks(f64, f64),
    Spectral(Filter),
    File(PathBuf),
}

fn params(text: &str, rest: &str, allowed: &[&str]) -> Result<Vec<(String, f64)>> {
    let mut out = Vec::new();
    for item in rest.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let (k, v) = item
            .split_once('=')
            .ok_or_else(|| anyhow::anyhow!("--signature {text}: '{item}' should be name=value"))?;
        let k = k.trim();
        if !allowed.contains(&k) {
            bail!(
                "--signature {text}: unknown parameter '{k}' (expected {})",
                allowed.join(", ")
            );
        }
        let v: f64 = v
            .trim()
            .parse()
            .map_err(|_| anyhow::anyhow!("--signature {text}: '{v}' is not a number"))?;
        if !v.is_finite() {
            bail!("--signature {text}: {k} must be finite");
        }
        out.push((k.to_string(), v));
    }
    Ok(out)
}

fn get(p: &[(String, f64)], k: &str) -> Option<f64> {
    p.iter().find(|(n, _)| n == k).map(|(_, v)| *v)
}

fn parse_source(text: &str) -> Result<Source> {
    let t = text.trim();
    let (name, rest) = t.split_once(':').unwrap_or((t, ""));
    let positive = |what: &str, v: f64| -> Result<f64> {
        if v > 0.0 {
            Ok(v)
        } else {
            bail!("--signature {text}: {what} must be positive")
        }
    };
    Ok(match name.trim().to_ascii_lowercase().as_str() {
        "hks" => Source::Hks(positive(
            "t",
            get(&params(text, rest, &["t"])?, "t").unwrap_or(0.1),
        )?),
        "adf" => Source::Adf(positive(
            "t",
            get(&params(text, rest, &["t"])?, "t").unwrap_or(0.1),
        )?),
        "wks" => {
            let p = params(text, rest, &["e", "sigma"])?;
            let e = get(&p, "e").ok_or_else(|| {
                anyhow::anyhow!("--signature {text}: wks needs e=ENERGY (and sigma=)")
            })?;
            Source::Wks(e, positive("sigma", get(&p, "sigma").unwrap_or(0.5))?)
        }
        "biharmonic-function" | "biharmonic" => Source::Spectral(Filter::Biharmonic),
        "commute-function" | "commute" => Source::Spectral(Filter::CommuteTime),
        "spectral-function" => Source::Spectral(
            rest.parse::<Filter>()
                .map_err(|e| anyhow::anyhow!("--signature {text}: {e}"))?,
        ),
        "field" | "file" => {
            if rest.is_empty() {
                bail!("--signature {text}: field needs a file, field:FILE");
            }
            Source::File(PathBuf::from(rest))
        }
        other => bail!(
            "--signature {text}: unknown signature '{other}' (expected hks, adf, wks, biharmonic-function, commute-function, spectral-function:FILTER or field:FILE)"
        ),
    })
}

/// A colour per label: hues spaced by the golden ratio, alternating value so that
/// neighbouring labels stay distinguishable.
pub fn label_colors(labels: &[usize]) -> Vec<[f32; 3]> {
    const GOLDEN: f64 = 0.618_033_988_749_895;
    labels
        .iter()
        .map(|&l| {
            let h = (l as f64 * GOLDEN).fract() * 360.0;
            let v = if (l / 7) % 2 == 0 { 0.95 } else { 0.7 };
            let s = if l % 2 == 0 { 0.75 } else { 0.55 };
            hsv_to_rgb(h, s, v).map(|c| c as f32)
        })
        .collect()
}

fn labels_text(labels: &[usize]) -> String {
    let mut s = String::with_capacity(labels.len() * 3);
    for l in labels {
        s.push_str(&l.to_string());
        s.push('\n');
    }
    s
}

/// Segments and writes the outputs.
pub fn run(args: Args) -> Result<()> {
    let input = input::load(args.mesh.as_deref())?;
    let mesh = &input.mesh;
    let n = mesh.n_vertices();
    let src = parse_source(&args.signature)?;
    if !(args.persistence.is_finite() && args.persistence >= 0.0) {
        bail!(
            "--persistence {}: must be a number >= 0 (a fraction of the field's range)",
            args.persistence
        );
    }
    check_outputs(&args.out, &FIGURE_EXTS, args.force)?;
    if let Some(p) = &args.field_out {
        check_outputs(std::slice::from_ref(p), &["txt"], args.force)?;
    }
    let (field, eigen_note) = match &src {
        Source::File(p) => (read_field(p, n)?, String::new()),
        _ => {
            let tb = args.basis.compute(mesh, None)?;
            let b = normalized(&tb.basis, args.no_normalize);
            let f = match &src {
                Source::Hks(t) => hks(&b, &[*t], false).swap_remove(0),
                Source::Adf(t) => auto_diffusion(&b, *t)?,
                Source::Wks(e, s) => wks(&b, &[*e], *s, false)?.swap_remove(0),
                Source::Spectral(f) => spectral_function(&b, f)
                    .map_err(|e| anyhow::anyhow!("--signature {}: {e}", args.signature))?,
                Source::File(_) => unreachable!("handled above"),
            };
            (
                f,
                format!(
                    ", k = {} ({}), eigenpairs in {:.2} s",
                    tb.basis.k(),
                    tb.basis.laplacian,
                    tb.seconds
                ),
            )
        }
    };
    let seg = segment(
        mesh,
        &field,
        SegmentParams {
            persistence: args.persistence,
        },
    )?;
    println!(
        "{}: n = {n}; segmented {} with persistence {}{eigen_note}",
        input.label(),
        args.signature,
        args.persistence
    );
    println!("patches: {}", seg.n_patches);
    let mut sizes = vec![0usize; seg.n_patches];
    for &l in &seg.labels {
        sizes[l] += 1;
    }
    for (i, ((g, m), s)) in seg
        .patch_genus
        .iter()
        .zip(&seg.maxima)
        .zip(&sizes)
        .enumerate()
    {
        let g = match g {
            Some(g) => g.to_string(),
            None => "undefined (no triangle, or not an orientable manifold)".into(),
        };
        println!("  patch {i}: {s} vertices, maximum at vertex {m}, genus {g}");
    }
    let labels_f: Vec<f64> = seg.labels.iter().map(|&l| l as f64).collect();
    let figure_args = FigureArgs {
        levels: 0,
        no_critical_points: true,
        ..args.figure.clone()
    };
    let mut fig = Figure::new(mesh, &labels_f, seg.maxima.clone(), &figure_args)?;
    fig.colors = Some(label_colors(&seg.labels));
    for o in &args.out {
        if extension(o).as_deref() == Some("txt") {
            write_atomic(o, labels_text(&seg.labels).as_bytes())?;
        } else {
            fig.write_by_extension(o, &figure_args)?;
        }
        println!("-> {}", o.display());
    }
    if let Some(p) = &args.field_out {
        write_field(p, &field)?;
    }
    Ok(())
}

fn write_field(p: &Path, f: &[f64]) -> Result<()> {
    write_atomic(p, crate::output::field_text(f).as_bytes())?;
    println!("field -> {}", p.display());
    Ok(())
}
