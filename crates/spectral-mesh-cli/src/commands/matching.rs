//! `spectral-mesh match SOURCE TARGET -k 30 --zoomout 100 -o map.txt`: a point-to-point
//! map from SOURCE to TARGET through the functional map of the two eigenbases (the
//! library's `correspondence` module: descriptors, the exact functional map, ZoomOut).
//!
//! In the library's terms the TARGET is shape 1 and the SOURCE shape 2: the map written
//! is `p2p_21` (for each source vertex a target vertex) and the functional map `C`
//! (`k_source x k_target`) carries functions on the target to functions on the source
//! (the pull-back by the map). With `--zoomout-direction reverse|both` the reverse map
//! `p2p_12` (for each target vertex a source vertex) is refined too and `--reverse-out`
//! writes it.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use spectral_mesh::analysis::{Analysis, AnalysisOptions};
use spectral_mesh::correspondence::descriptors::{
    DEFAULT_DESCRIPTOR_COUNT, DEFAULT_SUBSAMPLE_STEP, DescriptorKind,
};
use spectral_mesh::correspondence::energy::{
    DEFAULT_W_COMMUTATIVITY, DEFAULT_W_DESCRIPTORS, DEFAULT_W_LAPLACIAN, DEFAULT_W_ORIENTATION,
};
use spectral_mesh::correspondence::{
    DEFAULT_K, DEFAULT_ZOOMOUT_DIRECTION, DEFAULT_ZOOMOUT_K, DEFAULT_ZOOMOUT_STEP,
    DescriptorParams, FmapWeights, MatchParams, ZoomoutDirection, cumulative_curve,
    default_thresholds, fmap_to_p2p_12, geodesic_errors, match_shapes, parse_point_map,
    point_map_text,
};
use spectral_mesh::geodesic::{GeodesicParams, GeodesicSolver};
use spectral_mesh::spectral::eigenbasis::EigenParams;
use spectral_mesh::spectral::store::npy_f64;
use spectral_mesh::{Laplacian, Mesh};
use spectral_mesh_render::pair::render_pair;
use spectral_mesh_render::raster::RenderOptions;

use crate::engine::{self, resolve_laplacian};
use crate::input;
use crate::output::{check_writable, write};

/// The match pipeline's options, shared by `match` and `match-pairs`.
#[derive(Debug, clap::Args)]
pub struct MatchFlags {
    /// Size of both bases of the first functional map.
    #[arg(long, short = 'k', default_value_t = DEFAULT_K)]
    pub k: usize,
    /// ZoomOut: refine up to this basis size (0 or <= k: no refinement).
    #[arg(long, default_value_t = DEFAULT_ZOOMOUT_K)]
    pub zoomout: usize,
    /// ZoomOut step.
    #[arg(long, default_value_t = DEFAULT_ZOOMOUT_STEP)]
    pub step: usize,
    /// Which map ZoomOut refines: forward (a target vertex per source vertex), reverse (a
    /// source vertex per target vertex) or both.
    #[arg(long, default_value_t = DEFAULT_ZOOMOUT_DIRECTION)]
    pub zoomout_direction: ZoomoutDirection,
    /// Descriptor: wks or hks.
    #[arg(long, default_value_t = DescriptorKind::default())]
    pub descriptor: DescriptorKind,
    /// Number of descriptor energies (times).
    #[arg(long, default_value_t = DEFAULT_DESCRIPTOR_COUNT)]
    pub descriptors: usize,
    /// Keep every n-th descriptor.
    #[arg(long, default_value_t = DEFAULT_SUBSAMPLE_STEP)]
    pub subsample: usize,
    /// Weight of descriptor preservation.
    #[arg(long, default_value_t = DEFAULT_W_DESCRIPTORS)]
    pub w_descr: f64,
    /// Weight of Laplacian commutativity.
    #[arg(long, default_value_t = DEFAULT_W_LAPLACIAN)]
    pub w_lap: f64,
    /// Weight of descriptor commutativity.
    #[arg(long, default_value_t = DEFAULT_W_COMMUTATIVITY)]
    pub w_dcomm: f64,
    /// Weight of the orientation term (relative to the rest at the identity).
    #[arg(long, default_value_t = DEFAULT_W_ORIENTATION)]
    pub w_orient: f64,
    /// Use the orientation-reversing term (for a mirrored target).
    #[arg(long)]
    pub orient_reversing: bool,
    /// Discretization (default: fem).
    #[arg(long)]
    pub laplacian: Option<Laplacian>,
    /// Use the shapes as given instead of scaled to unit area.
    #[arg(long)]
    pub no_normalize: bool,
}

impl MatchFlags {
    /// The library's parameters of these flags, checked.
    pub fn params(&self) -> Result<MatchParams> {
        let params = MatchParams {
            k: self.k,
            zoomout_k: self.zoomout,
            zoomout_step: self.step,
            zoomout_direction: self.zoomout_direction,
            descriptors: DescriptorParams {
                kind: self.descriptor,
                count: self.descriptors,
                subsample_step: self.subsample,
            },
            weights: FmapWeights {
                descriptors: self.w_descr,
                laplacian: self.w_lap,
                commutativity: self.w_dcomm,
                orientation: self.w_orient,
                orientation_reversing: self.orient_reversing,
                ..FmapWeights::default()
            },
        };
        params.validate().map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok(params)
    }
}

/// Arguments of `match`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The mesh whose vertices are mapped (file or built-in shape).
    pub source: String,
    /// The mesh they are mapped onto.
    pub target: String,
    #[command(flatten)]
    pub flags: MatchFlags,
    /// Landmarks: a text file of lines `SOURCE_VERTEX TARGET_VERTEX` (0-based).
    #[arg(long)]
    pub landmarks: Option<PathBuf>,
    /// Keep computed bases in this folder and reuse them.
    #[arg(long)]
    pub cache: Option<PathBuf>,
    /// The map: one target vertex per source vertex, 0-based, one per line.
    #[arg(long, short = 'o')]
    pub out: Option<PathBuf>,
    /// The reverse map (with --zoomout-direction reverse or both): one source vertex per
    /// target vertex, 0-based, one per line.
    #[arg(long)]
    pub reverse_out: Option<PathBuf>,
    /// The refined functional map as .npy (k_source x k_target, float64).
    #[arg(long)]
    pub fmap: Option<PathBuf>,
    /// The reverse refined functional map as .npy (k_target x k_source, float64; with
    /// --zoomout-direction reverse or both).
    #[arg(long)]
    pub reverse_fmap: Option<PathBuf>,
    /// The first functional map (before ZoomOut) as .npy (k x k, float64).
    #[arg(long)]
    pub initial_fmap: Option<PathBuf>,
    /// A picture (.png): both shapes side by side, the source coloured by its
    /// coordinates, the target by the colours the map carries to it.
    #[arg(long)]
    pub picture: Option<PathBuf>,
    /// A true map (same format as -o): prints the mean geodesic error on the target in
    /// units of sqrt(area) and the cumulative curve.
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Overwrite existing outputs.
    #[arg(long, short = 'f')]
    pub force: bool,
}

fn load_mesh(spec: &str) -> Result<Mesh> {
    let (mesh, _) = input::load(Some(spec))?.into_mesh("match")?;
    Ok(mesh)
}

/// Computes the map and writes it.
pub fn run(args: Args) -> Result<()> {
    let t0 = Instant::now();
    let outputs = [
        &args.out,
        &args.reverse_out,
        &args.fmap,
        &args.reverse_fmap,
        &args.initial_fmap,
        &args.picture,
    ];
    if args.truth.is_none() && outputs.iter().all(|o| o.is_none()) {
        bail!("nothing to do: give -o MAP.txt, --fmap C.npy, --picture P.png or --truth MAP.txt");
    }
    if !args.flags.zoomout_direction.reverse()
        && (args.reverse_out.is_some() || args.reverse_fmap.is_some())
    {
        bail!(
            "--reverse-out and --reverse-fmap need the reverse map: give --zoomout-direction reverse or both"
        );
    }
    for p in outputs.into_iter().flatten() {
        check_writable(p, args.force)?;
    }
    let params = args.flags.params()?;
    let source = load_mesh(&args.source)?;
    let target = load_mesh(&args.target)?;
    let kb = params.basis_size();
    for (name, m) in [(&args.source, &source), (&args.target, &target)] {
        if kb > m.n_vertices() {
            bail!(
                "{name}: {kb} eigenpairs are needed (max of -k and --zoomout), the mesh has {} vertices",
                m.n_vertices()
            );
        }
    }
    let landmarks: Vec<(usize, usize)> = match &args.landmarks {
        None => Vec::new(),
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("{}: cannot read", p.display()))?;
            // Lines "source target": shape 1 is the target.
            spectral_mesh::correspondence::parse_landmarks(
                &text,
                &p.display().to_string(),
                source.n_vertices(),
                target.n_vertices(),
            )?
            .into_iter()
            .map(|(s, t)| (t, s))
            .collect()
        }
    };
    let truth = match &args.truth {
        None => None,
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("{}: cannot read", p.display()))?;
            Some(parse_point_map(
                &text,
                &p.display().to_string(),
                source.n_vertices(),
                target.n_vertices(),
            )?)
        }
    };
    let analysis = |mesh: Mesh| -> Result<Analysis> {
        let input = spectral_mesh::analysis::AnalysisInput::Mesh(mesh);
        let options = AnalysisOptions {
            laplacian: resolve_laplacian(args.flags.laplacian, &input)?,
            normalize: !args.flags.no_normalize,
            eigen: EigenParams::default(),
        };
        Ok(Analysis::from_input(input, options)?)
    };
    let an_target = analysis(target)?;
    let an_source = analysis(source)?;
    let b_target = engine::basis(&an_target, kb, args.cache.as_deref())?;
    let b_source = engine::basis(&an_source, kb, args.cache.as_deref())?;
    let (v1, v2) = (b_target.basis.view(kb), b_source.basis.view(kb));
    let t1 = Instant::now();
    let res = match_shapes(
        an_target.mesh(),
        v1,
        an_source.mesh(),
        v2,
        &landmarks,
        &params,
    )
    .map_err(|e| anyhow::anyhow!("{e}"))?;
    println!(
        "{} ({} vertices) -> {} ({} vertices): k = {}, ZoomOut to {}; eigenpairs in {:.2} s + {:.2} s, map in {:.2} s (energy {:.4e})",
        args.source,
        an_source.n(),
        args.target,
        an_target.n(),
        params.k,
        res.refined.k1,
        b_target.seconds,
        b_source.seconds,
        t1.elapsed().as_secs_f64(),
        res.energy
    );
    let reverse = res.reverse.as_ref();
    for (o, map, what) in [
        (&args.out, Some(&res.p2p_21), "map"),
        (&args.reverse_out, reverse.map(|r| &r.p2p), "reverse map"),
    ] {
        if let (Some(o), Some(map)) = (o, map) {
            write(o, point_map_text(map).as_bytes())?;
            println!("{what} ({} lines) -> {}", map.len(), o.display());
        }
    }
    for (o, c) in [
        (&args.fmap, Some(&res.refined)),
        (&args.reverse_fmap, reverse.map(|r| &r.fmap)),
        (&args.initial_fmap, Some(&res.initial)),
    ] {
        if let (Some(o), Some(c)) = (o, c) {
            let bytes = npy_f64(&c.row_major(), &[c.k2 as u64, c.k1 as u64], false)?;
            write(o, &bytes)?;
            println!("functional map ({} x {}) -> {}", c.k2, c.k1, o.display());
        }
    }
    if let Some(o) = &args.picture {
        // For each target vertex a source vertex, to carry the source's colours: the
        // refined reverse map when there is one.
        let back = match reverse {
            Some(r) => r.p2p.clone(),
            None => fmap_to_p2p_12(&res.refined, v1, v2).map_err(|e| anyhow::anyhow!("{e}"))?,
        };
        let img = render_pair(
            an_source.mesh(),
            an_target.mesh(),
            &back,
            &RenderOptions::default(),
        )?;
        write(o, &img.png_bytes()?)?;
        println!("picture -> {}", o.display());
    }
    if let Some(gt) = &truth {
        let solver = GeodesicSolver::new(
            an_target.mesh(),
            an_target.options().laplacian,
            &GeodesicParams::default(),
        )
        .map_err(|e| anyhow::anyhow!("geodesics on the target: {e}"))?;
        let e = geodesic_errors(&solver, &res.p2p_21, gt, an_target.mesh().area(), None)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        let th = default_thresholds();
        let curve = cumulative_curve(&e.errors, &th);
        let exact = e.errors.iter().filter(|&&x| x == 0.0).count();
        println!(
            "against {}: mean geodesic error {:.4e} sqrt(area) over {} vertices ({} exact, {} geodesic solves)",
            args.truth
                .as_ref()
                .map_or(String::new(), |p| p.display().to_string()),
            e.mean,
            e.errors.len(),
            exact,
            e.sources
        );
        let at = |t: f64| th.iter().position(|&x| x >= t).map_or(1.0, |i| curve[i]);
        println!(
            "cumulative: {:.1}% within 0.01, {:.1}% within 0.05, {:.1}% within 0.1 sqrt(area)",
            100.0 * at(0.01),
            100.0 * at(0.05),
            100.0 * at(0.1)
        );
    }
    println!("done in {:.2} s", t0.elapsed().as_secs_f64());
    Ok(())
}
