//! `spectral-mesh eigs MESH -k K --laplacian L -o basis.npz`: compute, check and save an
//! eigenbasis. Also holds the basis options and output checks shared by `heat`,
//! `distance`, `signature`, `segment` and `embed`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use spectral_mesh::linalg::EigenProgress;
use spectral_mesh::mesh::topology::Topology;
use spectral_mesh::spectral::Eigenbasis;
use spectral_mesh::spectral::eigenbasis::EigenParams;
use spectral_mesh::spectral::filters::ZERO_EIGENVALUE_EPS;
use spectral_mesh::spectral::heat::{ScaleNormalization, normalize_basis};
use spectral_mesh::spectral::store::{BasisMeta, load_or_compute, save_npz};
use spectral_mesh::{Laplacian, Mesh, Operators};

use crate::basis::{self, TimedBasis};
use crate::output::{check_writable, field_text, write_atomic};
use crate::{input, progress};

/// How to compute the eigenbasis a command works on.
#[derive(Debug, Clone, clap::Args)]
pub struct BasisArgs {
    /// Number of eigenpairs (the smallest eigenvalues).
    #[arg(long, short = 'k', default_value_t = 100)]
    pub k: usize,
    /// Discretization: cot, voronoi-cot, fem, mixed-voronoi, uniform.
    #[arg(long, default_value = "fem")]
    pub laplacian: Laplacian,
    /// Target relative residual of every eigenpair.
    #[arg(long, default_value_t = 1e-10)]
    pub tolerance: f64,
    /// Keep computed bases in this folder and reuse them (keyed by the mesh, the
    /// discretization and the parameters).
    #[arg(long)]
    pub cache: Option<PathBuf>,
}

impl BasisArgs {
    /// The solver parameters.
    pub fn params(&self, dirichlet: Option<Vec<usize>>) -> Result<EigenParams> {
        if self.k == 0 {
            bail!("-k 0: at least one eigenpair is needed");
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            bail!("--tolerance {}: must be a positive number", self.tolerance);
        }
        Ok(EigenParams {
            k: self.k,
            tolerance: self.tolerance,
            dirichlet,
            ..EigenParams::default()
        })
    }

    /// Computes (or loads from the cache) the basis of `mesh`.
    pub fn compute(&self, mesh: &Mesh, dirichlet: Option<Vec<usize>>) -> Result<TimedBasis> {
        let params = self.params(dirichlet)?;
        if params.k > mesh.n_vertices() {
            bail!(
                "-k {}: the mesh has only {} vertices",
                params.k,
                mesh.n_vertices()
            );
        }
        match &self.cache {
            Some(dir) => cached(dir, mesh, self.laplacian, &params),
            None => basis::compute(mesh, self.laplacian, &params),
        }
    }
}

/// `store::load_or_compute` with the progress bar of [`basis::compute`]; says on stdout
/// whether the basis came from the cache.
fn cached(
    dir: &Path,
    mesh: &Mesh,
    laplacian: Laplacian,
    params: &EigenParams,
) -> Result<TimedBasis> {
    let ops = Operators::new(mesh, laplacian);
    let bar = progress::bar(params.k as u64, "eigenpairs");
    let t0 = Instant::now();
    let mut cb = |p: EigenProgress| match p {
        EigenProgress::Dense { .. } => bar.set_message("dense eigen"),
        EigenProgress::Factorization { .. } => bar.set_message("factoring"),
        EigenProgress::Iteration { converged, .. } => {
            bar.set_message("iterating");
            bar.set_position(converged as u64);
        }
        _ => {}
    };
    let (basis, hit) = load_or_compute(dir, mesh, &ops, params, &mut cb)
        .with_context(|| format!("--cache {}", dir.display()))?;
    bar.finish_and_clear();
    println!(
        "eigenbasis {} cache {}",
        if hit {
            "loaded from"
        } else {
            "computed and stored in"
        },
        dir.display()
    );
    Ok(TimedBasis {
        basis,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// `--no-normalize` as a normalisation.
pub fn normalization(no_normalize: bool) -> ScaleNormalization {
    if no_normalize {
        ScaleNormalization::None
    } else {
        ScaleNormalization::UnitArea
    }
}

/// The basis scaled to unit area unless `no_normalize`.
pub fn normalized(basis: &Eigenbasis, no_normalize: bool) -> Eigenbasis {
    normalize_basis(basis, normalization(no_normalize))
}

/// The default anchor/source: the vertex of largest x (lowest index on ties).
pub fn default_vertex(mesh: &Mesh) -> usize {
    let p = mesh.positions();
    (0..p.len()).fold(0, |best, i| if p[i][0] > p[best][0] { i } else { best })
}

/// Refuses a vertex index out of range, naming the option.
pub fn check_vertex(v: usize, mesh: &Mesh, option: &str) -> Result<()> {
    if v >= mesh.n_vertices() {
        bail!(
            "{option} {v}: the mesh has only {} vertices",
            mesh.n_vertices()
        );
    }
    Ok(())
}

/// Lower-case extension of a path.
pub fn extension(p: &Path) -> Option<String> {
    p.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
}

/// Checks before any work that every output has one of the `allowed` extensions, is
/// named once, and may be written (not existing unless `force`).
pub fn check_outputs(outs: &[PathBuf], allowed: &[&str], force: bool) -> Result<()> {
    for (i, o) in outs.iter().enumerate() {
        match extension(o) {
            Some(e) if allowed.contains(&e.as_str()) => {}
            _ => bail!(
                "{}: unknown output type (use {})",
                o.display(),
                allowed
                    .iter()
                    .map(|e| format!(".{e}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        }
        if outs[..i].contains(o) {
            bail!("{}: named twice as an output", o.display());
        }
        check_writable(o, force)?;
    }
    Ok(())
}

/// Outputs a per-vertex field can be written to.
pub const FIGURE_EXTS: [&str; 5] = ["png", "wrl", "vrml", "ply", "txt"];

/// Arguments of `eigs`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Mesh file or built-in shape (default: the 3-torus).
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
    #[arg(long, default_value_t = 1e-6)]
    pub cluster_tolerance: f64,
    /// Repair the mesh first (see `info --repair`).
    #[arg(long)]
    pub repair: bool,
    /// Overwrite existing outputs.
    #[arg(long, short = 'f')]
    pub force: bool,
}

/// Groups of consecutive eigenvalues whose gaps are at most `tol * max(1, |lambda|)`
/// relative to the larger magnitude; returns `(first index, count)` of each group.
pub fn clusters(values: &[f64], tol: f64) -> Vec<(usize, usize)> {
    let scale = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut out: Vec<(usize, usize)> = Vec::new();
    for (i, &v) in values.iter().enumerate() {
        let joins = i > 0 && {
            let prev = values[i - 1];
            let mag = v.abs().max(prev.abs()).max(ZERO_EIGENVALUE_EPS * scale);
            (v - prev).abs() <= tol * mag
        };
        match out.last_mut() {
            Some(last) if joins => last.1 += 1,
            _ => out.push((i, 1)),
        }
    }
    out
}

/// Computes the basis and prints its summary.
pub fn run(args: Args) -> Result<()> {
    let input = input::load_repaired(args.mesh.as_deref(), args.repair)?;
    let mesh = &input.mesh;
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
    if !(args.cluster_tolerance.is_finite() && args.cluster_tolerance >= 0.0) {
        bail!(
            "--cluster-tolerance {}: must be a number >= 0",
            args.cluster_tolerance
        );
    }
    let topo = Topology::new(mesh);
    let dirichlet = if args.dirichlet_boundary {
        let b = topo.boundary_vertices();
        if b.is_empty() {
            bail!(
                "--dirichlet-boundary: {} has no boundary (it is closed)",
                input.label()
            );
        }
        Some(b)
    } else {
        None
    };
    let n_dirichlet = dirichlet.as_ref().map_or(0, Vec::len);
    let free = mesh.n_vertices() - n_dirichlet;
    if args.basis.k > free {
        bail!(
            "-k {}: only {free} vertices are free (the mesh has {} vertices, {n_dirichlet} on the Dirichlet boundary)",
            args.basis.k,
            mesh.n_vertices()
        );
    }
    let tb = args.basis.compute(mesh, dirichlet.clone())?;
    let b = &tb.basis;
    let (max_res, orth) = basis::quality(b);
    let min_res = b.residuals.iter().copied().fold(f64::INFINITY, f64::min);
    let lmax = b.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let zeros = b
        .values
        .iter()
        .filter(|v| v.abs() <= ZERO_EIGENVALUE_EPS * lmax)
        .count();
    // Components that touch no Dirichlet vertex each carry one zero eigenvalue.
    let expected_zeros = match &dirichlet {
        None => topo.n_components(),
        Some(d) => {
            let mut pinned = vec![false; topo.n_components()];
            for &v in d {
                if let Some(&c) = topo.vertex_component.get(v)
                    && let Some(p) = pinned.get_mut(c)
                {
                    *p = true;
                }
            }
            pinned.iter().filter(|p| !**p).count()
        }
    };

    println!(
        "{}: n = {}, m = {}, {} discretization{}",
        input.label(),
        mesh.n_vertices(),
        mesh.n_triangles(),
        b.laplacian,
        if n_dirichlet > 0 {
            format!(", Dirichlet on {n_dirichlet} boundary vertices")
        } else {
            String::new()
        }
    );
    println!("k = {} eigenpairs in {:.3} s", b.k(), tb.seconds);
    println!(
        "eigenvalues: {:.6e} .. {:.6e}",
        b.values.first().copied().unwrap_or(f64::NAN),
        b.values.last().copied().unwrap_or(f64::NAN)
    );
    println!("relative residuals: min {min_res:.2e}, max {max_res:.2e}");
    println!("orthogonality error max |X^T B X - I| = {orth:.2e}");
    println!(
        "near-zero eigenvalues (|lambda| <= {ZERO_EIGENVALUE_EPS:e} lambda_max): {zeros}; expected {expected_zeros} ({} components{}){}",
        topo.n_components(),
        if n_dirichlet > 0 {
            ", minus those pinned by Dirichlet"
        } else {
            ""
        },
        if zeros == expected_zeros {
            ""
        } else {
            "  <-- MISMATCH"
        }
    );
    let groups: Vec<(usize, usize)> = clusters(&b.values, args.cluster_tolerance)
        .into_iter()
        .filter(|g| g.1 > 1)
        .collect();
    if groups.is_empty() {
        println!(
            "clusters (relative gap <= {:e}): none, all eigenvalues simple",
            args.cluster_tolerance
        );
    } else {
        println!(
            "clusters (relative gap <= {:e}): {}",
            args.cluster_tolerance,
            groups
                .iter()
                .map(|&(i, c)| format!("{:.6} x{c} [{}..{}]", b.values[i], i, i + c - 1))
                .collect::<Vec<_>>()
                .join(", ")
        );
        if let Some(&(i, c)) = groups.last()
            && i + c == b.k()
        {
            println!("note: the last cluster reaches k; it may continue beyond the computed pairs");
        }
    }

    if let Some(p) = &args.out {
        save(b, mesh, &args.basis.params(dirichlet)?, p)?;
        println!("basis -> {}", p.display());
    }
    if let Some(p) = &args.eigenvalues_txt {
        write_atomic(p, field_text(&b.values).as_bytes())?;
        println!("eigenvalues -> {}", p.display());
    }
    if let Some(p) = &args.plot {
        let title = format!("{} spectrum, {} ({})", input.label(), b.laplacian, b.k());
        spectral_mesh_render::plots::plot_spectrum(p, &b.values, &title)
            .with_context(|| format!("{}: cannot plot the spectrum", p.display()))?;
        println!("spectrum plot -> {}", p.display());
    }
    Ok(())
}

/// Saves through a temporary file in the same folder and a rename.
fn save(b: &Eigenbasis, mesh: &Mesh, params: &EigenParams, p: &Path) -> Result<()> {
    let dir = p
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = p
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "basis.npz".into());
    let tmp = dir.join(format!(".{name}.tmp-{}.npz", std::process::id()));
    let meta = BasisMeta::new(b, Some(mesh), params);
    if let Err(e) = save_npz(b, &tmp, &meta) {
        let _ = std::fs::remove_file(&tmp);
        bail!("{}: cannot save the basis: {e}", p.display());
    }
    std::fs::rename(&tmp, p).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        anyhow::anyhow!("{}: cannot write: {e}", p.display())
    })
}
