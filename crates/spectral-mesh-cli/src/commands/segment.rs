//! `spectral-mesh segment MESH --signature hks:t=0.1 --persistence 0.05 -o labels.txt`:
//! patches = watershed basins of the maxima of a signature, with persistence merging.

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use spectral_mesh::analysis::request::DEFAULT_PERSISTENCE;
use spectral_mesh::analysis::{FieldRequest, SignatureSpec};
use spectral_mesh::fields::segmentation::patch_genera;
use spectral_mesh_render::figure::field_text;

use crate::engine::{self, FieldBasisArgs};
use crate::field_output::FieldOutputArgs;
use crate::input::read_field;
use crate::output::{check_outputs, write};

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
    /// Mesh file, point-cloud file (.xyz/.pts/.txt/.csv, or a PLY without faces) or
    /// built-in shape (default: the 3-torus).
    pub mesh: Option<String>,
    /// The field to segment (see below).
    #[arg(long, default_value_t = SignatureSpec::default().to_string(), long_help = SIGNATURE_HELP)]
    pub signature: String,
    /// Merge threshold relative to the field's range: basins whose maximum rises less
    /// than this above their saddle join their elder neighbour.
    #[arg(long, default_value_t = DEFAULT_PERSISTENCE)]
    pub persistence: f64,
    #[command(flatten)]
    pub spectral: FieldBasisArgs,
    /// Output file(s): .txt (labels, one per line), or .png, .wrl, .ply (patches in
    /// distinct colours), repeatable.
    #[arg(long, short = 'o', required = true)]
    pub out: Vec<PathBuf>,
    /// Also write the segmented field, one value per line.
    #[arg(long)]
    pub field_out: Option<PathBuf>,
    #[command(flatten)]
    pub output: FieldOutputArgs,
}

/// `--signature`: `field:FILE` read here, anything else parsed by the library.
fn signature(text: &str, n: usize) -> Result<SignatureSpec> {
    let t = text.trim();
    if let Some(file) = t.strip_prefix("field:").or_else(|| t.strip_prefix("file:")) {
        if file.is_empty() {
            bail!("--signature {text}: field needs a file, field:FILE");
        }
        return Ok(SignatureSpec::Values(read_field(Path::new(file), n)?));
    }
    t.parse()
        .map_err(|e| anyhow::anyhow!("--signature {text}: {e}"))
}

/// The request of the segmented field itself.
fn signature_request(spec: &SignatureSpec, k: usize) -> Option<FieldRequest> {
    Some(match spec {
        SignatureSpec::Hks { t } => FieldRequest::Hks {
            t: *t,
            scaled: false,
            k,
        },
        SignatureSpec::Adf { t } => FieldRequest::Adf { t: *t, k },
        SignatureSpec::Wks { e, sigma } => FieldRequest::Wks {
            energy: *e,
            sigma: *sigma,
            scaled: false,
            k,
        },
        SignatureSpec::Spectral(f) => FieldRequest::SpectralFunction {
            filter: f.clone(),
            k,
        },
        SignatureSpec::Values(_) => return None,
    })
}

/// Segments and writes the outputs.
pub fn run(args: Args) -> Result<()> {
    let input = args.spectral.basis.load(args.mesh.as_deref())?;
    let n = input.n();
    let spec = signature(&args.signature, n)?;
    let request = FieldRequest::Segmentation {
        signature: spec.clone(),
        persistence: args.persistence,
        k: args.spectral.basis.k,
    };
    request.validate().map_err(|e| anyhow::anyhow!("--{e}"))?;
    args.output.check(&args.out)?;
    if let Some(p) = &args.field_out {
        check_outputs(std::slice::from_ref(p), &["txt"], args.output.force)?;
    }
    args.spectral
        .basis
        .warn_unrecorded(args.output.save_experiment.as_ref());
    let info = input.info;
    let an = args.spectral.analysis(input.shape)?;
    let (field, seconds) = engine::field(&an, &request, args.spectral.basis.cache.as_deref())
        .map_err(|e| anyhow::anyhow!("--signature {}: {e:#}", args.signature))?;
    let labels = field.labels.clone().unwrap_or_default();
    let n_patches = labels.iter().max().map_or(0, |m| m + 1);
    let eigen_note = match request.eigenpairs() {
        Some(k) => format!(
            ", k = {k} ({}), eigenpairs in {seconds:.2} s",
            an.options().laplacian
        ),
        None => String::new(),
    };
    println!(
        "{}: n = {n}; segmented {} with persistence {}{eigen_note}",
        info.label(),
        args.signature,
        args.persistence
    );
    println!("patches: {n_patches}");
    let mut sizes = vec![0usize; n_patches];
    for &l in &labels {
        sizes[l] += 1;
    }
    let genera = patch_genera(an.mesh(), &labels, n_patches);
    for (i, ((g, m), s)) in genera.iter().zip(&field.marks).zip(&sizes).enumerate() {
        let g = match g {
            Some(g) => g.to_string(),
            None => "undefined (no triangle, or not an orientable manifold)".into(),
        };
        println!("  patch {i}: {s} vertices, maximum at vertex {m}, genus {g}");
    }
    args.output.write_field(&an, &field, &args.out)?;
    if let Some(p) = &args.field_out {
        let values = match (&spec, signature_request(&spec, args.spectral.basis.k)) {
            (SignatureSpec::Values(v), _) => v.clone(),
            (_, Some(r)) => an.field(&r)?.values,
            (_, None) => Vec::new(),
        };
        write(p, field_text(&values).as_bytes())?;
        println!("field -> {}", p.display());
    }
    args.output
        .save_experiment(&info, &an, &field, args.spectral.basis.repair)?;
    Ok(())
}
