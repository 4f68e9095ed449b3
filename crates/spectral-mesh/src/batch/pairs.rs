//! Matching over pairs of a collection: the library's match pipeline
//! ([`crate::correspondence::match_shapes`]) on each pair chosen by a [`Pairing`], one
//! point-map file and one [`PairRecord`] per pair, and the CSV of the records. The faces
//! (the command line's `match-pairs`, Python's `match_pairs`, locally or on Dask) only
//! resolve the inputs, run [`process_pair`] on each [`PairJob`] and write the summary with
//! [`write_pairs_summary`].
//!
//! # Layout of the output folder
//! ```text
//! OUT/maps/NAME.txt           the point map of a pair: for each source vertex a target
//!                             vertex, 0-based, one per line (`match -o`'s format)
//! OUT/maps/NAME.reverse.txt   for each target vertex a source vertex (ZoomOut's reverse
//!                             direction, when asked for)
//! OUT/pairs.csv               one row per pair (see PAIR_COLUMNS)
//! OUT/.spectral-mesh-batch    marks the folder as a batch output folder
//! ```
//! `NAME` is `SOURCE--TARGET`, the inputs' names (see [`super::BatchInput::name`]) with
//! `/` replaced by `_`. As in `match SOURCE TARGET`, the target is shape 1 and the source
//! shape 2 of the correspondence module: the map is `p2p_21`. Unlike the shapes of
//! [`super::process_one`], pairs are not resumed: a run computes and replaces every map.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Instant;

use super::params::SolveParams;
use super::record::Status;
use super::{BatchError, BatchInput};
use crate::analysis::Analysis;
use crate::cancel::CancelToken;
use crate::correspondence::{
    MatchParams, geodesic_errors, match_shapes, parse_point_map, point_map_text,
};
use crate::geodesic::{GeodesicParams, GeodesicSolver};
use crate::io::{read_mesh, write_atomic_durable};
use crate::operators::Laplacian;

/// The summary file of a pair batch, in the output folder.
pub const PAIRS_CSV: &str = "pairs.csv";
/// The folder of the maps, in the output folder.
pub const MAPS_FOLDER: &str = "maps";
/// Default cap on the geodesic solves of one pair's evaluation (see
/// [`crate::correspondence::geodesic_errors`]'s `max_sources`).
pub const DEFAULT_PAIR_GEODESIC_SOURCES: usize = 1000;

/// One pair of an explicit list: source and target each an input's name, its path as
/// given, or its 0-based position in the list of inputs; `truth` a true point map (one
/// target vertex per source vertex, 0-based, one per line).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct PairSpec {
    /// The shape whose vertices are mapped.
    pub source: String,
    /// The shape they are mapped onto.
    pub target: String,
    /// A ground-truth map, for the mean geodesic error.
    #[serde(default)]
    pub truth: Option<PathBuf>,
}

/// Which pairs of the inputs (in their resolved order) are matched.
#[derive(Debug, Clone, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Pairing {
    /// Every unordered pair `(i, j)`, `i < j`: input `i` the source, `j` the target.
    #[default]
    All,
    /// Inputs `i` and `i + 1`, for each `i`.
    Consecutive,
    /// The pairs listed.
    List(Vec<PairSpec>),
}

impl FromStr for Pairing {
    type Err = String;
    /// `all` or `consecutive` (a list is read with [`parse_pair_list`]).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "all" => Ok(Self::All),
            "consecutive" => Ok(Self::Consecutive),
            other => Err(format!(
                "unknown pairing '{other}': use all, consecutive or a list of pairs"
            )),
        }
    }
}

/// Reads a pair list: lines `SOURCE TARGET [TRUTH]` (blank lines and `#` comments
/// skipped), SOURCE and TARGET as in [`PairSpec`], TRUTH a file taken relative to `base`
/// (the list's folder). `file` labels the errors.
pub fn parse_pair_list(text: &str, file: &str, base: &Path) -> Result<Vec<PairSpec>, BatchError> {
    let mut pairs = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let words: Vec<&str> = line
            .split('#')
            .next()
            .unwrap_or("")
            .split_whitespace()
            .collect();
        match words.as_slice() {
            [] => {}
            [s, t] | [s, t, _] => pairs.push(PairSpec {
                source: s.to_string(),
                target: t.to_string(),
                truth: words.get(2).map(|p| base.join(p)),
            }),
            _ => {
                return Err(BatchError::Input {
                    spec: format!("{file}:{}", i + 1),
                    message: format!(
                        "expected SOURCE TARGET [TRUTH], found {} values",
                        words.len()
                    ),
                });
            }
        }
    }
    Ok(pairs)
}

/// One pair to match, with everything a worker needs (plain data: it crosses processes).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct PairJob {
    /// `SOURCE--TARGET` (see the module docs).
    pub name: String,
    /// The source file.
    pub source: PathBuf,
    /// The source's name among the inputs.
    pub source_name: String,
    /// The target file.
    pub target: PathBuf,
    /// The target's name among the inputs.
    pub target_name: String,
    /// A ground-truth map file.
    pub truth: Option<PathBuf>,
}

impl PairJob {
    /// The map file: `out/maps/NAME.txt`.
    pub fn map_path(&self, out: &Path) -> PathBuf {
        out.join(MAPS_FOLDER).join(format!("{}.txt", self.name))
    }

    /// The reverse map file: `out/maps/NAME.reverse.txt`.
    pub fn reverse_map_path(&self, out: &Path) -> PathBuf {
        out.join(MAPS_FOLDER)
            .join(format!("{}.reverse.txt", self.name))
    }
}

/// The jobs of `pairing` over `inputs` (in order: by source, then target, for `All`).
/// A list entry naming no input is an error of the batch.
pub fn plan_pairs(inputs: &[BatchInput], pairing: &Pairing) -> Result<Vec<PairJob>, BatchError> {
    let n = inputs.len();
    let indices: Vec<(usize, usize, Option<PathBuf>)> = match pairing {
        Pairing::All => (0..n)
            .flat_map(|i| (i + 1..n).map(move |j| (i, j, None)))
            .collect(),
        Pairing::Consecutive => (1..n).map(|j| (j - 1, j, None)).collect(),
        Pairing::List(list) => list
            .iter()
            .map(|p| {
                Ok((
                    find(inputs, &p.source)?,
                    find(inputs, &p.target)?,
                    p.truth.clone(),
                ))
            })
            .collect::<Result<_, BatchError>>()?,
    };
    if indices.is_empty() {
        return Err(BatchError::Input {
            spec: format!("{n} inputs"),
            message: "no pairs to match (at least two inputs are needed)".into(),
        });
    }
    let file_name = |s: &str| s.replace('/', "_");
    Ok(indices
        .into_iter()
        .map(|(i, j, truth)| {
            let (s, t) = (&inputs[i], &inputs[j]);
            PairJob {
                name: format!("{}--{}", file_name(&s.name), file_name(&t.name)),
                source: s.path.clone(),
                source_name: s.name.clone(),
                target: t.path.clone(),
                target_name: t.name.clone(),
                truth,
            }
        })
        .collect())
}

/// The input `key` names: its name, its path as given, or its position.
fn find(inputs: &[BatchInput], key: &str) -> Result<usize, BatchError> {
    inputs
        .iter()
        .position(|b| b.name == key || b.path == Path::new(key))
        .or_else(|| key.parse::<usize>().ok().filter(|&i| i < inputs.len()))
        .ok_or_else(|| BatchError::Input {
            spec: key.to_string(),
            message: format!(
                "names none of the {} inputs (give a name, a path or a position from 0)",
                inputs.len()
            ),
        })
}

crate::defaults::declare::with_defaults! {
    /// Parameters of a pair batch. `Default`: the match defaults, the analysis defaults
    /// (fem, unit area, the eigensolver's tolerance), at most
    /// [`DEFAULT_PAIR_GEODESIC_SOURCES`] geodesic solves per evaluation. In JSON the keys of
    /// [`SolveParams`] stand beside the others.
    #[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
    #[serde(default)]
    pub struct PairParams {
        /// The match pipeline's parameters.
        pub matching: MatchParams = MatchParams::default(),
        /// How both shapes are solved (for [`MatchParams::basis_size`] pairs).
        #[serde(flatten)]
        pub solve: SolveParams = SolveParams::default(),
        /// Most geodesic solves of an evaluation (`None`: every wrongly mapped vertex).
        pub max_geodesic_sources: Option<usize> = Some(DEFAULT_PAIR_GEODESIC_SOURCES),
    }
}

impl PairParams {
    /// Checks the ranges.
    pub fn validate(&self) -> Result<(), BatchError> {
        let param = |key, message: String| BatchError::Parameter { key, message };
        self.matching
            .validate()
            .map_err(|e| param("matching", e.to_string()))?;
        if self.solve.laplacian == Laplacian::Robust {
            return Err(param(
                "laplacian",
                "the robust Laplacian is for point clouds; pairs are meshes".into(),
            ));
        }
        self.solve.validate()
    }
}

/// The defaults of a pair batch as JSON: [`PairParams::default`] and, under `pairing`,
/// [`Pairing::default`] (the `pairs` entry of [`crate::defaults::to_json`]).
pub fn defaults_json() -> serde_json::Value {
    let mut v = serde_json::to_value(PairParams::default()).unwrap_or_default();
    if let Some(o) = v.as_object_mut() {
        o.insert(
            "pairing".into(),
            serde_json::to_value(Pairing::default()).unwrap_or_default(),
        );
    }
    v
}

/// The sizes of a pair and of its maps.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PairSizes {
    /// Source vertices.
    pub n_source: Option<usize>,
    /// Target vertices.
    pub n_target: Option<usize>,
    /// Size of the first functional map's bases.
    pub k: usize,
    /// Size of the refined maps (`k` without ZoomOut).
    pub k_final: Option<usize>,
}

/// The seconds of each stage of a pair, and of the whole.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PairTimings {
    /// Reading both meshes.
    pub read_seconds: f64,
    /// Computing both eigenbases.
    pub basis_seconds: f64,
    /// The match pipeline (descriptors, map, ZoomOut, point maps).
    pub match_seconds: f64,
    /// The evaluation against the truth.
    pub eval_seconds: f64,
    /// Wall seconds of the pair in all.
    pub seconds: f64,
}

/// The row of one pair: what a worker returns (small); the maps are in the files named.
/// In JSON the keys of [`PairSizes`] and [`PairTimings`] stand beside the others (the
/// columns of `pairs.csv`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PairRecord {
    /// The pair's name (`SOURCE--TARGET`).
    pub name: String,
    /// The source's name among the inputs.
    pub source: String,
    /// The target's name among the inputs.
    pub target: String,
    /// Ok or failed.
    pub status: Status,
    /// Why it failed, naming the file (`None` unless failed).
    pub error: Option<String>,
    /// The sizes of the meshes and of the maps.
    #[serde(flatten)]
    pub sizes: PairSizes,
    /// ZoomOut's direction (`forward`, `reverse`, `both`).
    pub direction: String,
    /// Energy of the first functional map.
    pub energy: Option<f64>,
    /// Mean geodesic error of the map on the target, in units of `sqrt(area)` (with a
    /// ground truth).
    pub mean_geodesic_error: Option<f64>,
    /// Share of the source vertices mapped to their true vertex (with a ground truth).
    pub exact_share: Option<f64>,
    /// Where the time went.
    #[serde(flatten)]
    pub timings: PairTimings,
    /// Files written, relative to the output folder.
    pub outputs: Vec<String>,
}

impl PairRecord {
    /// An empty row for `job` (failed until filled in).
    pub fn new(job: &PairJob, params: &PairParams) -> Self {
        Self {
            name: job.name.clone(),
            source: job.source_name.clone(),
            target: job.target_name.clone(),
            status: Status::Failed,
            error: None,
            sizes: PairSizes {
                n_source: None,
                n_target: None,
                k: params.matching.k,
                k_final: None,
            },
            direction: params.matching.zoomout_direction.to_string(),
            energy: None,
            mean_geodesic_error: None,
            exact_share: None,
            timings: PairTimings::default(),
            outputs: Vec::new(),
        }
    }

    /// A failed row with `message` (e.g. a Dask task that failed: made by the face).
    pub fn failed(job: &PairJob, params: &PairParams, message: impl Into<String>) -> Self {
        Self {
            error: Some(message.into()),
            ..Self::new(job, params)
        }
    }
}

/// Matches one pair and writes its maps (see the module docs); never panics: a bad
/// mesh, a failed solve or a panic becomes a failed row whose error names the file.
/// `cancel` stops the eigensolvers (the row then says so).
pub fn process_pair(
    job: &PairJob,
    params: &PairParams,
    out: &Path,
    cancel: &CancelToken,
) -> PairRecord {
    let t0 = Instant::now();
    let mut rec = PairRecord::new(job, params);
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        run_pair(job, params, out, cancel, &mut rec)
    }));
    match outcome {
        Ok(Ok(())) => rec.status = Status::Ok,
        Ok(Err(message)) => rec.error = Some(message),
        Err(panic) => rec.error = Some(super::panic_message(&*panic)),
    }
    rec.timings.seconds = t0.elapsed().as_secs_f64();
    rec
}

fn run_pair(
    job: &PairJob,
    params: &PairParams,
    out: &Path,
    cancel: &CancelToken,
    rec: &mut PairRecord,
) -> Result<(), String> {
    params.validate().map_err(|e| e.to_string())?;
    let t = Instant::now();
    let read = |p: &Path| read_mesh(p).map(|l| l.mesh).map_err(|e| e.to_string());
    let (source, target) = (read(&job.source)?, read(&job.target)?);
    rec.sizes.n_source = Some(source.n_vertices());
    rec.sizes.n_target = Some(target.n_vertices());
    let truth = match &job.truth {
        None => None,
        Some(p) => {
            let label = p.display().to_string();
            let text =
                std::fs::read_to_string(p).map_err(|e| format!("{label}: cannot read: {e}"))?;
            Some(
                parse_point_map(&text, &label, source.n_vertices(), target.n_vertices())
                    .map_err(|e| e.to_string())?,
            )
        }
    };
    rec.timings.read_seconds = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let kb = params.matching.basis_size();
    let options = params.solve.analysis_options(kb);
    let solve = |mesh, path: &Path| {
        let an = Analysis::new(mesh, options.clone());
        let basis = an
            .basis(kb, &mut |_| {}, cancel)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        Ok::<_, String>((an, basis))
    };
    let (an_target, b_target) = solve(target, &job.target)?;
    let (an_source, b_source) = solve(source, &job.source)?;
    rec.timings.basis_seconds = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let res = match_shapes(
        an_target.mesh(),
        b_target.view(kb),
        an_source.mesh(),
        b_source.view(kb),
        &[],
        &params.matching,
    )
    .map_err(|e| format!("{} -> {}: {e}", job.source.display(), job.target.display()))?;
    rec.timings.match_seconds = t.elapsed().as_secs_f64();
    rec.energy = Some(res.energy);
    rec.sizes.k_final = Some(
        res.refined
            .k1
            .max(res.reverse.as_ref().map_or(0, |r| r.fmap.k1)),
    );
    let write = |path: PathBuf, map: &[usize], rec: &mut PairRecord| {
        write_atomic_durable(&path, point_map_text(map).as_bytes()).map_err(|e| e.to_string())?;
        rec.outputs.push(relative(&path, out));
        Ok::<_, String>(())
    };
    if let Some(dir) = job.map_path(out).parent() {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("{}: cannot create: {e}", dir.display()))?;
    }
    write(job.map_path(out), &res.p2p_21, rec)?;
    if let Some(r) = &res.reverse {
        write(job.reverse_map_path(out), &r.p2p, rec)?;
    }
    if let Some(gt) = truth {
        let t = Instant::now();
        let mesh = an_target.mesh();
        let solver = GeodesicSolver::new(mesh, params.solve.laplacian, &GeodesicParams::default())
            .map_err(|e| format!("{}: geodesics: {e}", job.target.display()))?;
        let e = geodesic_errors(
            &solver,
            &res.p2p_21,
            &gt,
            mesh.area(),
            params.max_geodesic_sources,
        )
        .map_err(|e| e.to_string())?;
        rec.mean_geodesic_error = Some(e.mean);
        let exact = res.p2p_21.iter().zip(&gt).filter(|(a, b)| a == b).count();
        rec.exact_share = Some(exact as f64 / gt.len().max(1) as f64);
        rec.timings.eval_seconds = t.elapsed().as_secs_f64();
    }
    Ok(())
}

fn relative(p: &Path, out: &Path) -> String {
    p.strip_prefix(out)
        .unwrap_or(p)
        .to_string_lossy()
        .replace('\\', "/")
}

/// The columns of `pairs.csv`, in order (the fields of [`PairRecord`]; `outputs` joined
/// by `;`; empty cells for unknown values).
pub const PAIR_COLUMNS: [&str; 19] = [
    "name",
    "source",
    "target",
    "status",
    "error",
    "n_source",
    "n_target",
    "k",
    "k_final",
    "direction",
    "energy",
    "mean_geodesic_error",
    "exact_share",
    "read_seconds",
    "basis_seconds",
    "match_seconds",
    "eval_seconds",
    "seconds",
    "outputs",
];

/// The records as CSV text: a header, then one line per record in the given order
/// (cells with a comma, a quote or a line break quoted as in RFC 4180).
pub fn pairs_csv(records: &[PairRecord]) -> String {
    let text = |s: &str| super::summary::csv_cell(s);
    let num = |v: Option<f64>| v.map(|x| format!("{x:?}")).unwrap_or_default();
    let int = |v: Option<usize>| v.map(|x| x.to_string()).unwrap_or_default();
    let mut s = PAIR_COLUMNS.join(",");
    s.push('\n');
    for r in records {
        let cells = [
            text(&r.name),
            text(&r.source),
            text(&r.target),
            r.status.to_string(),
            text(r.error.as_deref().unwrap_or("")),
            int(r.sizes.n_source),
            int(r.sizes.n_target),
            r.sizes.k.to_string(),
            int(r.sizes.k_final),
            text(&r.direction),
            num(r.energy),
            num(r.mean_geodesic_error),
            num(r.exact_share),
            num(Some(r.timings.read_seconds)),
            num(Some(r.timings.basis_seconds)),
            num(Some(r.timings.match_seconds)),
            num(Some(r.timings.eval_seconds)),
            num(Some(r.timings.seconds)),
            text(&r.outputs.join(";")),
        ];
        s.push_str(&cells.join(","));
        s.push('\n');
    }
    s
}

/// Writes `out/pairs.csv` ([`pairs_csv`]); returns its path.
pub fn write_pairs_summary(out: &Path, records: &[PairRecord]) -> Result<PathBuf, BatchError> {
    let path = out.join(PAIRS_CSV);
    write_atomic_durable(&path, pairs_csv(records).as_bytes())
        .map_err(|e| BatchError::Write(e.to_string()))?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::correspondence::ZoomoutDirection;
    use crate::io::{WriteOptions, write_mesh};
    use crate::mesh::Mesh;

    /// An icosphere deformed without any symmetry.
    fn blob(res: u32) -> Mesh {
        crate::shapes::build_str(&format!("sphere:res={res}"))
            .unwrap()
            .map_positions(|[x, y, z]| {
                [
                    1.6 * x + 0.35 * x * x + 0.2 * y,
                    0.9 * y + 0.25 * z * z,
                    0.7 * z + 0.3 * x * y + 0.15 * z * z * z,
                ]
            })
            .unwrap()
    }

    fn input(dir: &Path, name: &str) -> BatchInput {
        BatchInput {
            path: dir.join(name),
            name: name.to_string(),
        }
    }

    fn small_params(direction: ZoomoutDirection) -> PairParams {
        let mut p = PairParams::default();
        p.matching.k = 20;
        p.matching.zoomout_k = 40;
        p.matching.zoomout_direction = direction;
        p
    }

    #[test]
    fn pairs_of_shuffled_copies_and_a_bad_mesh() {
        let d = tempfile::tempdir().unwrap();
        let src = d.path().join("in");
        std::fs::create_dir(&src).unwrap();
        let base = blob(3);
        let (copy, perm) = crate::correspondence::shuffled_copy(&base, 5).unwrap();
        write_mesh(&src.join("blob.off"), &base, &WriteOptions::default()).unwrap();
        write_mesh(&src.join("copy.off"), &copy, &WriteOptions::default()).unwrap();
        std::fs::write(
            src.join("broken.off"),
            "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n",
        )
        .unwrap();
        std::fs::write(src.join("truth.txt"), point_map_text(&perm)).unwrap();
        let inputs = [
            input(&src, "blob.off"),
            input(&src, "broken.off"),
            input(&src, "copy.off"),
        ];
        let list = parse_pair_list(
            "# source target truth\ncopy.off blob.off truth.txt\n1 0\n",
            "pairs.txt",
            &src,
        )
        .unwrap();
        let jobs = plan_pairs(&inputs, &Pairing::List(list)).unwrap();
        assert_eq!(jobs.len(), 2);
        assert_eq!(jobs[0].name, "copy.off--blob.off");
        assert_eq!(
            jobs[0].truth.as_deref(),
            Some(src.join("truth.txt").as_path())
        );
        let out = d.path().join("out");
        super::super::prepare_output(&out, false).unwrap();
        let params = small_params(ZoomoutDirection::Both);
        let recs: Vec<PairRecord> = jobs
            .iter()
            .map(|j| process_pair(j, &params, &out, &CancelToken::new()))
            .collect();
        let ok = &recs[0];
        assert_eq!(ok.status, Status::Ok, "{:?}", ok.error);
        let n = base.n_vertices();
        assert_eq!(
            (ok.sizes.n_source, ok.sizes.n_target, ok.sizes.k_final),
            (Some(n), Some(n), Some(40))
        );
        assert!(ok.energy.is_some_and(|e| e.is_finite() && e >= 0.0));
        let err = ok.mean_geodesic_error.unwrap();
        assert!(err < 0.01, "mean geodesic error {err}");
        assert!(ok.exact_share.unwrap() > 0.99, "{:?}", ok.exact_share);
        assert_eq!(
            ok.outputs,
            [
                "maps/copy.off--blob.off.txt",
                "maps/copy.off--blob.off.reverse.txt"
            ]
        );
        // The map file: one target vertex per source vertex, as `match -o` writes it.
        let text = std::fs::read_to_string(jobs[0].map_path(&out)).unwrap();
        let map = parse_point_map(&text, "map", n, n).unwrap();
        let exact = map.iter().zip(&perm).filter(|(a, b)| a == b).count();
        assert!(exact as f64 > 0.99 * n as f64, "{exact} of {n}");
        let rtext = std::fs::read_to_string(jobs[0].reverse_map_path(&out)).unwrap();
        let rmap = parse_point_map(&rtext, "reverse", n, n).unwrap();
        let back = (0..n).filter(|&u| map[rmap[u]] == u).count();
        assert!(back as f64 > 0.99 * n as f64, "round trip {back} of {n}");
        // The bad mesh: a failed row naming the file and the line, no map.
        let bad = &recs[1];
        assert_eq!(bad.status, Status::Failed);
        let e = bad.error.as_deref().unwrap();
        assert!(e.contains("broken.off"), "{e}");
        assert!(bad.outputs.is_empty() && !jobs[1].map_path(&out).exists());
        // The CSV: the header and one line per pair.
        let csv_path = write_pairs_summary(&out, &recs).unwrap();
        let csv = std::fs::read_to_string(csv_path).unwrap();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 3);
        assert_eq!(lines[0], PAIR_COLUMNS.join(","));
        let cells: Vec<&str> = lines[1].split(',').collect();
        assert_eq!(cells.len(), PAIR_COLUMNS.len());
        let col = |name| PAIR_COLUMNS.iter().position(|c| *c == name).unwrap();
        assert_eq!(cells[col("status")], "ok");
        assert_eq!(cells[col("n_source")], n.to_string());
        assert_eq!(cells[col("direction")], "both");
        let parsed: f64 = cells[col("mean_geodesic_error")].parse().unwrap();
        assert_eq!(parsed, err);
        assert!(lines[2].contains("failed") && lines[2].contains("broken.off"));
    }

    #[test]
    fn pairings_and_lists() {
        let dir = Path::new("data");
        let inputs: Vec<BatchInput> = ["a.off", "sub/b.off", "c.off", "d.off"]
            .iter()
            .map(|n| input(dir, n))
            .collect();
        let names = |p: &Pairing| -> Vec<String> {
            plan_pairs(&inputs, p)
                .unwrap()
                .into_iter()
                .map(|j| j.name)
                .collect()
        };
        assert_eq!(names(&Pairing::All).len(), 6);
        assert_eq!(names(&Pairing::All)[0], "a.off--sub_b.off");
        assert_eq!(
            names(&Pairing::Consecutive),
            ["a.off--sub_b.off", "sub_b.off--c.off", "c.off--d.off"]
        );
        assert_eq!("Consecutive".parse::<Pairing>(), Ok(Pairing::Consecutive));
        assert!(
            "some"
                .parse::<Pairing>()
                .unwrap_err()
                .contains("all, consecutive")
        );
        // By name, by path, by position.
        let list =
            parse_pair_list("sub/b.off data/c.off\n3 0 t.txt # a comment\n\n", "l", dir).unwrap();
        assert_eq!(list[1].truth.as_deref(), Some(Path::new("data/t.txt")));
        assert_eq!(
            names(&Pairing::List(list)),
            ["sub_b.off--c.off", "d.off--a.off"]
        );
        let unknown = Pairing::List(vec![PairSpec {
            source: "e.off".into(),
            target: "4".into(),
            truth: None,
        }]);
        let e = plan_pairs(&inputs, &unknown).unwrap_err().to_string();
        assert!(e.contains("e.off") && e.contains("names none"), "{e}");
        let e = parse_pair_list("a b c d\n", "pairs.txt", dir)
            .unwrap_err()
            .to_string();
        assert!(e.contains("pairs.txt:1"), "{e}");
        assert!(plan_pairs(&inputs[..1], &Pairing::All).is_err());
        // The serde forms the faces send.
        let p: Pairing =
            serde_json::from_str(r#"{"list": [{"source": "0", "target": "1"}]}"#).unwrap();
        assert_eq!(names(&p), ["a.off--sub_b.off"]);
        let p: Pairing = serde_json::from_str(r#""consecutive""#).unwrap();
        assert_eq!(p, Pairing::Consecutive);
    }

    #[test]
    fn parameters_are_checked_and_default_to_the_library() {
        let p = PairParams::default();
        assert_eq!(p.matching, MatchParams::default());
        assert_eq!(
            p.solve.laplacian,
            crate::analysis::AnalysisOptions::default().laplacian
        );
        assert!(p.validate().is_ok());
        let mut bad = PairParams::default();
        bad.solve.laplacian = Laplacian::Robust;
        assert!(
            bad.validate()
                .unwrap_err()
                .to_string()
                .contains("laplacian")
        );
        let mut bad = PairParams::default();
        bad.matching.k = 1;
        assert!(bad.validate().unwrap_err().to_string().contains("matching"));
        let j = crate::defaults::to_json();
        let p: PairParams = serde_json::from_value(j["pairs"].clone()).unwrap();
        assert_eq!(p, PairParams::default());
        assert_eq!(j["pairs"]["pairing"], "all");
    }
}
