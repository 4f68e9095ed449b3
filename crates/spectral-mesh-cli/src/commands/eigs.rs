//! `spectral-mesh eigs MESH -k K --laplacian L -o basis.npz`: compute, check and save an
//! eigenbasis of the shape as given (not scaled to unit area: the raw operators, as SciPy
//! sees them).

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use spectral_mesh::cancel::CancelToken;
use spectral_mesh::experiments::paper::BasisReport;
use spectral_mesh::spectral::eigenbasis::{EigenParams, Eigenbasis, certify_eigenbasis};
use spectral_mesh::spectral::filters::ZERO_EIGENVALUE_EPS;
use spectral_mesh::spectral::store::{BasisDtype, BasisMeta, save_npz};
use spectral_mesh::{Analysis, AnalysisOptions};
use spectral_mesh_render::figure::field_text;

use crate::engine::{self, BasisArgs};
use crate::output::{check_writable, extension, write};

/// Arguments of `eigs`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file, point-cloud file (.xyz/.pts/.txt/.csv, PLY without faces) or built-in
    /// shape (default: the 3-torus).
    pub mesh: Option<String>,
    #[command(flatten)]
    pub basis: BasisArgs,
    /// Save the basis as a NumPy .npz archive (eigenvalues, eigenvectors, mass, metadata).
    #[arg(long, short = 'o')]
    pub out: Option<PathBuf>,
    /// Zero Dirichlet condition on the boundary vertices (the mesh must have a boundary).
    #[arg(long)]
    pub dirichlet_boundary: bool,
    /// Write the eigenvalues, one per line.
    #[arg(long)]
    pub eigenvalues_txt: Option<PathBuf>,
    /// Plot the spectrum (eigenvalue against index) to a .png or .svg file.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Relative gap below which consecutive eigenvalues count as one cluster.
    #[arg(long, default_value_t = spectral_mesh::defaults::CLUSTER_TOLERANCE)]
    pub cluster_tolerance: f64,
    /// Floating-point type of the eigenvalues and eigenvectors in the .npz (float64 or
    /// float32): computed in double precision either way and rounded once when written.
    #[arg(long, default_value = BasisDtype::default().name())]
    pub dtype: String,
    /// Certify that no eigenvalue was skipped, multiplicities included: count the
    /// eigenvalues below a shift just above lambda_k from the negative pivots of an
    /// L D L^T factorization of S - sigma B (Sylvester's law of inertia) and compare; when
    /// they disagree, search for the missing pairs and certify again (the completed basis
    /// is the one saved). Exits with an error when the count still disagrees.
    #[arg(long)]
    pub certify: bool,
    /// Overwrite existing outputs.
    #[arg(long, short = 'f')]
    pub force: bool,
}

/// Computes the basis and prints its summary.
pub fn run(args: Args) -> Result<()> {
    let mut stages = Stages::new();
    let input = args.basis.load(args.mesh.as_deref())?;
    stages.done("read");
    for p in [&args.out, &args.eigenvalues_txt, &args.plot]
        .into_iter()
        .flatten()
    {
        check_writable(p, args.force)?;
    }
    if let Some(p) = &args.out
        && extension(p).as_deref() != Some("npz")
    {
        bail!("{}: the basis is saved as .npz", p.display());
    }
    if let Some(p) = &args.plot
        && !matches!(extension(p).as_deref(), Some("png") | Some("svg"))
    {
        bail!("{}: the spectrum plot is .png or .svg", p.display());
    }
    let dtype = BasisDtype::parse(&args.dtype).map_err(|e| anyhow::anyhow!("--dtype: {e}"))?;
    if dtype != BasisDtype::Float64 && args.out.is_none() {
        bail!(
            "--dtype {}: applies to the .npz basis; give -o",
            dtype.name()
        );
    }
    if !(args.cluster_tolerance.is_finite() && args.cluster_tolerance >= 0.0) {
        bail!(
            "--cluster-tolerance {}: must be a number >= 0",
            args.cluster_tolerance
        );
    }
    let label = input.label();
    let cloud = input.info.point_cloud;
    let n = input.n();
    args.basis.check_k(n)?;
    // The options without Dirichlet vertices first: the boundary comes from the topology.
    let options = args.basis.options(&input.shape, false, None)?;
    let mut an = Analysis::from_input(input.shape, options)?;
    stages.done("operators");
    let dirichlet = if args.dirichlet_boundary {
        let b = an.topology().boundary_vertices();
        if b.is_empty() {
            bail!("--dirichlet-boundary: {label} has no boundary (it is closed)");
        }
        let free = n - b.len();
        if args.basis.k > free {
            bail!(
                "-k {}: only {free} vertices are free (the mesh has {n} vertices, {} on the Dirichlet boundary)",
                args.basis.k,
                b.len()
            );
        }
        let options = AnalysisOptions {
            eigen: EigenParams {
                dirichlet: Some(b.clone()),
                ..an.options().eigen.clone()
            },
            ..an.options().clone()
        };
        an = Analysis::with_operators(an.mesh_arc().clone(), an.operators().clone(), options);
        Some(b)
    } else {
        None
    };
    stages.done("boundary");
    let solved = engine::basis(&an, args.basis.k, args.basis.cache.as_deref())?;
    stages.done("solve");
    let seconds = solved.seconds;
    let params = EigenParams {
        k: args.basis.k,
        ..an.options().eigen.clone()
    };
    let mut certify_lines = Vec::new();
    let mut certified = true;
    let completed = if args.certify {
        let t0 = std::time::Instant::now();
        let (completed, report) =
            certify_eigenbasis(an.operators(), &params, &solved.basis, &CancelToken::new())
                .context("--certify")?;
        certify_lines = report.lines();
        certify_lines.push(format!(
            "certificate time: {:.3} s",
            t0.elapsed().as_secs_f64()
        ));
        certified = report.certified();
        completed
    } else {
        None
    };
    stages.done("certify");
    let b: &Eigenbasis = completed.as_ref().unwrap_or(&solved.basis);
    // The solver's own orthogonality report when it computed the basis now.
    let r = BasisReport::with_orthogonality(
        b,
        an.components(),
        dirichlet.as_deref(),
        args.cluster_tolerance,
        // The solver's report is of the basis it returned, not of a completed one.
        if completed.is_some() {
            None
        } else {
            solved.orthogonality
        },
    );
    stages.done("check");
    let mesh = an.mesh();
    println!(
        "{label}: {}n = {n}, m = {}{}, {} discretization{}",
        match cloud {
            Some(p) => format!("point cloud ({} neighbours), ", p.neighbors),
            None => String::new(),
        },
        mesh.n_triangles(),
        if an.is_point_cloud() {
            " (triangle union)"
        } else {
            ""
        },
        b.laplacian,
        if r.dirichlet_vertices > 0 {
            format!(", Dirichlet on {} boundary vertices", r.dirichlet_vertices)
        } else {
            String::new()
        }
    );
    println!("k = {} eigenpairs in {seconds:.3} s", b.k());
    println!(
        "eigenvalues: {:.6e} .. {:.6e}",
        b.values.first().copied().unwrap_or(f64::NAN),
        b.values.last().copied().unwrap_or(f64::NAN)
    );
    if let (Some(lo), Some(hi)) = (r.min_relative_residual, r.max_relative_residual) {
        println!("relative residuals: min {lo:.2e}, max {hi:.2e}");
    }
    println!(
        "orthogonality error max |X^T B X - I| = {:.2e}",
        r.orthonormality_error
    );
    println!(
        "near-zero eigenvalues (|lambda| <= {ZERO_EIGENVALUE_EPS:e} lambda_max): {}; expected {} ({} components{}){}",
        r.near_zero,
        r.expected_near_zero,
        r.components,
        if r.dirichlet_vertices > 0 {
            ", minus those pinned by Dirichlet"
        } else {
            ""
        },
        if r.near_zero == r.expected_near_zero {
            ""
        } else {
            "  <-- MISMATCH"
        }
    );
    if r.clusters.is_empty() {
        println!(
            "clusters (relative gap <= {:e}): none, all eigenvalues simple",
            r.cluster_tolerance
        );
    } else {
        println!(
            "clusters (relative gap <= {:e}): {}",
            r.cluster_tolerance,
            r.clusters
                .iter()
                .map(|&(i, c)| format!("{:.6} x{c} [{}..{}]", b.values[i], i, i + c - 1))
                .collect::<Vec<_>>()
                .join(", ")
        );
        if r.last_cluster_reaches_k {
            println!("note: the last cluster reaches k; it may continue beyond the computed pairs");
        }
    }
    for l in &certify_lines {
        println!("{l}");
    }
    if let Some(p) = &args.out {
        save_npz(
            b,
            p,
            &BasisMeta::new(b, Some(mesh), &params).with_dtype(dtype),
        )
        .with_context(|| format!("{}: cannot save the basis", p.display()))?;
        println!("basis ({}) -> {}", dtype.name(), p.display());
    }
    stages.done("write");
    if let Some(p) = &args.eigenvalues_txt {
        write(p, field_text(&b.values).as_bytes())?;
        println!("eigenvalues -> {}", p.display());
    }
    if let Some(p) = &args.plot {
        let title = format!("{label} spectrum, {} ({})", b.laplacian, b.k());
        spectral_mesh_render::plots::plot_spectrum(p, &b.values, &title)
            .with_context(|| format!("{}: cannot plot the spectrum", p.display()))?;
        println!("spectrum plot -> {}", p.display());
    }
    stages.done("other outputs");
    stages.report();
    if !certified {
        bail!(
            "--certify: the eigenvalue count disagrees (see above); the outputs hold the pairs found"
        );
    }
    Ok(())
}

/// Wall seconds of the command's stages, printed to stderr when the solver's phase
/// timings are on (`SPECTRAL_MESH_EIG_TIMINGS=1`, see `spectral_mesh::linalg::timing`):
/// the whole process, next to the solver's own phases.
struct Stages {
    on: bool,
    last: std::time::Instant,
    done: Vec<(&'static str, f64)>,
}

impl Stages {
    fn new() -> Self {
        Self {
            on: spectral_mesh::linalg::timing::enabled(),
            last: std::time::Instant::now(),
            done: Vec::new(),
        }
    }

    /// Ends the stage `name` (the time since the previous one).
    fn done(&mut self, name: &'static str) {
        if self.on {
            let now = std::time::Instant::now();
            self.done
                .push((name, now.duration_since(self.last).as_secs_f64()));
            self.last = now;
        }
    }

    fn report(&self) {
        if self.on {
            let parts: Vec<String> = self
                .done
                .iter()
                .map(|(name, s)| format!("{name}={s:.3}"))
                .collect();
            eprintln!("eigs stages (s): {}", parts.join(" "));
        }
    }
}
