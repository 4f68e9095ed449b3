//! Every default of the command line is the library's: each argument's default of every
//! command (clap's command tree) against the library value it must equal, and no literal
//! default in the source of a command (a face states no default of its own).

use std::collections::BTreeMap;

use clap::CommandFactory;
use spectral_mesh::analysis::{DistanceSpec, SignatureSpec};
use spectral_mesh::batch::BatchParams;
use spectral_mesh::defaults::{self as d, server};
use spectral_mesh::experiments::harmonic::HarmonicExperimentParams;
use spectral_mesh::experiments::truncation::{TruncationParams, TruncationReference};
use spectral_mesh::geodesic::GeodesicParams;
use spectral_mesh::spectral::eigenbasis::EigenParams;
use spectral_mesh::spectral::filters::Filter;
use spectral_mesh::spectral::heat::Kernel;
use spectral_mesh::spectral::store::BasisDtype;
use spectral_mesh_render::figure::FigureOptions;

/// Arguments whose default is the face's own choice, not a library value: where output
/// goes, which column is drawn, which signature a bare `signature` computes; and the
/// truncation study's reference, the name of the library's `TruncationReference::default()`
/// (checked against it above). Named `file/field`; the literal scan allows these only.
const FACE_CHOICES: [&str; 6] = [
    "study.rs/reference",
    "operators.rs/out",
    "experiment.rs/out",
    "study.rs/out",
    "signature.rs/kind",
    "signature.rs/column",
];

fn s(v: impl ToString) -> Vec<String> {
    vec![v.to_string()]
}

/// Several values as text, in order.
fn list<T: ToString>(values: impl IntoIterator<Item = T>) -> Vec<String> {
    values.into_iter().map(|v| v.to_string()).collect()
}

/// The library's value of every argument with a default, by clap id, or by
/// `command path/id` where one id means different things in different commands.
fn library_values() -> BTreeMap<String, Vec<String>> {
    let fig = FigureOptions::default();
    let truncation = TruncationParams::default();
    let harmonic = HarmonicExperimentParams::default();
    let batch = BatchParams::default();
    let geodesic = GeodesicParams::default();
    let mut m: BTreeMap<String, Vec<String>> = BTreeMap::new();
    let mut put = |k: &str, v: Vec<String>| {
        m.insert(k.to_string(), v);
    };
    put("k", s(d::DEFAULT_K));
    put("tolerance", s(EigenParams::default().tolerance));
    put("levels", s(fig.levels));
    put("colormap", s(fig.colormap));
    put("size", s(fig.canvas.size));
    put("t", s(d::DEFAULT_HEAT_T));
    put("kernel", s(Kernel::default().name()));
    put("distance", s(DistanceSpec::default()));
    put("filter", s(Filter::default()));
    put("signature", s(SignatureSpec::default()));
    put("persistence", s(d::DEFAULT_PERSISTENCE));
    put("dims", s(d::EMBED_DIMS));
    put("cluster_tolerance", s(d::CLUSTER_TOLERANCE));
    put("dtype", s(BasisDtype::default().name()));
    put("time_factor", s(geodesic.time_factor));
    put("convention", s(geodesic.convention));
    put("constraints", list(&harmonic.constraint_counts));
    put("order", s(harmonic.order));
    put("batch/k", s(batch.k));
    put("batch/laplacian", s(batch.solve.laplacian));
    put("batch/tolerance", s(batch.solve.tolerance));
    put(
        "study truncation/laplacian",
        list(truncation.laplacians.iter().map(|l| l.name())),
    );
    put("study truncation/t", list(&truncation.times));
    put(
        "study truncation/k",
        list(truncation.ks.iter().map(|&k| {
            if k == usize::MAX {
                "all".to_string()
            } else {
                k.to_string()
            }
        })),
    );
    assert_eq!(truncation.reference, TruncationReference::Auto);
    put("study truncation/reference", s("auto"));
    // `match` and `match-pairs`: the library's correspondence defaults.
    for cmd in ["match", "match-pairs"] {
        use spectral_mesh::correspondence as c;
        let mut put = |k: &str, v: Vec<String>| put(&format!("{cmd}/{k}"), v);
        put("k", s(c::DEFAULT_K));
        put("zoomout", s(c::DEFAULT_ZOOMOUT_K));
        put("step", s(c::DEFAULT_ZOOMOUT_STEP));
        put("zoomout_direction", s(c::DEFAULT_ZOOMOUT_DIRECTION));
        put("descriptor", s(c::descriptors::DescriptorKind::default()));
        put("descriptors", s(c::descriptors::DEFAULT_DESCRIPTOR_COUNT));
        put("subsample", s(c::descriptors::DEFAULT_SUBSAMPLE_STEP));
        put("w_descr", s(c::energy::DEFAULT_W_DESCRIPTORS));
        put("w_lap", s(c::energy::DEFAULT_W_LAPLACIAN));
        put("w_dcomm", s(c::energy::DEFAULT_W_COMMUTATIVITY));
        put("w_orient", s(c::energy::DEFAULT_W_ORIENTATION));
    }
    put(
        "match-pairs/geodesic_sources",
        s(spectral_mesh::batch::PairParams::default()
            .max_geodesic_sources
            .unwrap_or(usize::MAX)),
    );
    // `serve`: the library's server limits.
    put("host", s(server::HOST));
    put("port", s(server::PORT));
    put("memory_mib", s(server::MEMORY_MIB));
    put("cache_mib", s(server::CACHE_MIB));
    put("max_upload_mib", s(server::MAX_UPLOAD_MIB));
    put("max_vertices", s(server::MAX_VERTICES));
    put("max_faces", s(server::MAX_FACES));
    put("max_k", s(server::MAX_K));
    put("max_jobs", s(server::MAX_JOBS));
    put("max_queued", s(server::MAX_QUEUED));
    put("job_seconds", s(server::JOB_SECONDS));
    put("job_idle_seconds", s(server::JOB_IDLE_SECONDS));
    put("request_seconds", s(server::REQUEST_SECONDS));
    put("max_requests", s(server::MAX_REQUESTS));
    put("idle_seconds", s(server::IDLE_SECONDS));
    m
}

/// (command path, arg id, its defaults) of every argument with a default.
fn defaults_of(cmd: &clap::Command, path: &str, out: &mut Vec<(String, String, Vec<String>)>) {
    for a in cmd.get_arguments() {
        let v: Vec<String> = a
            .get_default_values()
            .iter()
            .map(|x| x.to_string_lossy().into_owned())
            .collect();
        if !v.is_empty() {
            out.push((path.to_string(), a.get_id().to_string(), v));
        }
    }
    for sub in cmd.get_subcommands() {
        let p = if path.is_empty() {
            sub.get_name().to_string()
        } else {
            format!("{path} {}", sub.get_name())
        };
        defaults_of(sub, &p, out);
    }
}

#[test]
fn every_flag_default_is_the_librarys() {
    let lib = library_values();
    let mut args = Vec::new();
    defaults_of(&crate::Cli::command(), "", &mut args);
    assert!(args.len() > 40, "{} arguments with a default", args.len());
    let mut checked = 0;
    for (path, id, got) in &args {
        let top = path.split(' ').next().unwrap_or("");
        let key_full = format!("{path}/{id}");
        let key_top = format!("{top}/{id}");
        let want = lib
            .get(&key_full)
            .or_else(|| lib.get(&key_top))
            .or_else(|| lib.get(id.as_str()));
        match want {
            Some(w) => {
                assert_eq!(got, w, "`{path} --{id}`: the default is not the library's");
                checked += 1;
            }
            None => {
                let face = ["out", "column", "kind"].contains(&id.as_str());
                assert!(
                    face,
                    "`{path} --{id}` has the default {got:?} and no library value to check it \
                     against: read it from the library (spectral_mesh::defaults) and add it to \
                     library_values()"
                );
            }
        }
    }
    assert!(checked > 30, "{checked} checked");
}

/// The field name of the `pub NAME:` line after line `i`.
fn field_after(lines: &[&str], i: usize) -> String {
    lines[i..]
        .iter()
        .find_map(|l| {
            let t = l.trim();
            t.strip_prefix("pub ")
                .and_then(|r| r.split_once(':'))
                .map(|(n, _)| n.trim().to_string())
        })
        .unwrap_or_default()
}

#[test]
fn no_command_states_a_literal_default() {
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    for dir in [src.clone(), src.join("commands")] {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "rs") {
                files.push(p);
            }
        }
    }
    let literal_start = |e: &str| {
        e.starts_with(|c: char| c.is_ascii_digit() || c == '"' || c == '-' || c == '[')
            || e.starts_with("true")
            || e.starts_with("false")
            || e.starts_with("vec![")
            || e.starts_with('\'')
    };
    let mut bad = Vec::new();
    let mut seen = 0;
    for f in &files {
        let name = f.file_name().unwrap().to_string_lossy().into_owned();
        if name == "defaults_test.rs" {
            continue;
        }
        let text = std::fs::read_to_string(f).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            for key in [
                "default_value_t",
                "default_values_t",
                "default_value",
                "default_values",
            ] {
                let pat = format!("{key} =");
                let Some(pos) = line.find(&pat) else { continue };
                if line[..pos].ends_with('_') {
                    continue;
                }
                seen += 1;
                let expr = line[pos + pat.len()..].trim_start();
                let field = format!("{name}/{}", field_after(&lines, i));
                if literal_start(expr) && !FACE_CHOICES.contains(&field.as_str()) {
                    bad.push(format!("{field}: {}", line.trim()));
                }
                break;
            }
        }
    }
    assert!(seen > 30, "{seen} defaults found");
    assert!(
        bad.is_empty(),
        "literal defaults in the command line (read them from the library):\n{}",
        bad.join("\n")
    );
}
