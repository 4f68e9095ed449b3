//! The CLI is a face of the library's one engine: for every request kind the field the CLI
//! writes equals `Analysis::field` of the same request with every default left alone, a
//! field command's `--save-experiment` file replays to the same bytes, and `run` of a
//! saved field file reproduces it byte for byte.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

use spectral_mesh::analysis::{Analysis, AnalysisOptions, FieldRequest};
use spectral_mesh::shapes::build_str;

const SPHERE: &str = "sphere:res=2";

mod common;
use common::*;

fn request(json: &str) -> FieldRequest {
    serde_json::from_str(json).unwrap()
}

/// `Analysis::field` of `req` on the default analysis of `shape` (FEM, unit area).
fn library_field(shape: &str, req: &FieldRequest) -> Vec<f64> {
    Analysis::new(build_str(shape).unwrap(), AnalysisOptions::default())
        .field(req)
        .unwrap()
        .values
}

fn assert_close(cli: &[f64], lib: &[f64], what: &str) {
    assert_eq!(cli.len(), lib.len(), "{what}: lengths");
    let scale = lib.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    for (i, (a, b)) in cli.iter().zip(lib).enumerate() {
        assert!(
            (a - b).abs() <= 1e-12 * scale,
            "{what}: vertex {i}: CLI {a} against library {b}"
        );
    }
}

/// Writes an `experiment = "field"` file holding `[field]` `body` on `mesh`.
fn field_file(dir: &Path, name: &str, mesh: &str, body: &str) {
    let text = format!(
        "experiment = \"field\"\nmesh = \"{mesh}\"\n\n[figure]\nsize = 48\n\n[field]\n{body}"
    );
    std::fs::write(dir.join(name), text).unwrap();
}

#[test]
fn every_request_kind_written_by_the_cli_equals_the_librarys_field() {
    let mesh = build_str(SPHERE).unwrap();
    let n = mesh.n_vertices();
    // A signal for the diffusion: the height, as a field file.
    let signal: Vec<f64> = mesh.positions().iter().map(|q| q[2]).collect();
    let text: String = signal.iter().map(|v| format!("{v:?}\n")).collect();
    let d = folder_with("signal.txt", text);
    let p = d.path();
    let signal_json = serde_json::to_string(&signal).unwrap();

    for (name, kind) in [
        ("geo", "geodesic"),
        ("emb", "embedding"),
        ("eig", "eigenfunction"),
        ("green", "green"),
        ("harmonic", "harmonic"),
    ] {
        field_file(
            p,
            &format!("{name}.toml"),
            SPHERE,
            &format!("kind = \"{kind}\"\n"),
        );
    }
    // (CLI arguments, output written, the library's request with defaults only.)
    #[rustfmt::skip]
    let cases: Vec<(&str, &str, String)> = vec![
        ("heat sphere:res=2 -o heat.txt", "heat.txt", r#"{"kind": "heat"}"#.into()),
        ("heat sphere:res=2 --signal signal.txt -o diff.txt",
         "diff.txt", format!(r#"{{"kind": "diffusion", "signal": {{"values": {signal_json}}}}}"#)),
        ("heat sphere:res=2 --indicator 5,0.4 -o ball.txt",
         "ball.txt", r#"{"kind": "diffusion", "signal": {"ball": {"vertex": 5, "radius": 0.4}}}"#.into()),
        ("distance sphere:res=2 -o dist.txt", "dist.txt", r#"{"kind": "distance"}"#.into()),
        ("distance sphere:res=2 --distance wfem-diffusion -o wfem.txt",
         "wfem.txt", r#"{"kind": "distance", "distance": "wfem-diffusion"}"#.into()),
        ("signature sphere:res=2 -o hks.txt", "hks.txt", r#"{"kind": "hks"}"#.into()),
        ("signature sphere:res=2 --kind adf -o adf.txt", "adf.txt", r#"{"kind": "adf"}"#.into()),
        ("signature sphere:res=2 --kind wks --energies 5 -o wks.txt",
         "wks.txt", r#"{"kind": "wks", "energy": 5}"#.into()),
        ("signature sphere:res=2 --kind spectral-function -o sf.txt",
         "sf.txt", r#"{"kind": "spectral-function"}"#.into()),
        ("segment sphere:res=2 -o seg.txt", "seg.txt", r#"{"kind": "segmentation"}"#.into()),
        ("experiment harmonic sphere:res=2 --constraints 2 --size 32 -o harm",
         "harm/harmonic-field-1.txt", r#"{"kind": "harmonic"}"#.into()),
        ("run geo.toml -o geo", "geo/geodesic.txt", r#"{"kind": "geodesic"}"#.into()),
        ("run emb.toml -o emb", "emb/embedding.txt", r#"{"kind": "embedding"}"#.into()),
        ("run eig.toml -o eig", "eig/eigenfunction.txt", r#"{"kind": "eigenfunction"}"#.into()),
        ("run green.toml -o green", "green/green.txt", r#"{"kind": "green"}"#.into()),
        ("run harmonic.toml -o harmonic",
         "harmonic/harmonic.txt", r#"{"kind": "harmonic"}"#.into()),
    ];
    let mut kinds: Vec<&str> = Vec::new();
    for (args, out, json) in &cases {
        ok_in_with(p, args, &[]);
        let req = request(json);
        let cli = values(&p.join(out));
        assert_eq!(cli.len(), n);
        assert_close(&cli, &library_field(SPHERE, &req), out);
        kinds.push(req.kind());
    }
    kinds.sort_unstable();
    kinds.dedup();
    let mut all = spectral_mesh::analysis::request::KINDS.to_vec();
    all.sort_unstable();
    assert_eq!(kinds, all, "every request kind is covered");
}

/// `a` and `b` have the same bytes.
fn same_bytes(a: &Path, b: &Path) {
    let x = std::fs::read(a).unwrap_or_else(|e| panic!("{}: {e}", a.display()));
    let y = std::fs::read(b).unwrap_or_else(|e| panic!("{}: {e}", b.display()));
    assert!(x == y, "{} and {} differ", a.display(), b.display());
}

#[test]
fn save_experiment_on_each_field_command_replays_to_the_same_bytes() {
    let field: String = (0..162)
        .map(|i| format!("{}\n", (i as f64 * 0.37).sin()))
        .collect();
    let d = folder_with("f.txt", field);
    let p = d.path();
    // (command line without outputs, the kind the replay writes)
    #[rustfmt::skip]
    let cases: Vec<(&str, &str)> = vec![
        ("heat sphere:res=2 -k 30 --t 0.05", "heat"),
        ("heat sphere:res=2 -k 30 --indicator 3,0.5 --kernel voronoi-cot", "diffusion"),
        ("heat sphere:res=2 -k 30 --signal f.txt", "diffusion"),
        ("distance sphere:res=2 -k 30 --source 9 --distance mix:a=0.3,t=0.2 --no-normalize",
         "distance"),
        ("distance sphere:res=2 -k 25 --distance wfem-diffusion:t=0.05 --laplacian voronoi-cot",
         "distance"),
        ("signature sphere:res=2 -k 30 --kind wks --energies auto:4 --column 2 --scaled", "wks"),
        ("signature sphere:res=2 -k 30 --times auto:3 --column 1", "hks"),
        ("segment sphere:res=2 -k 30 --signature wks:e=4,sigma=0.4 --persistence 0.02",
         "segmentation"),
        ("segment sphere:res=2 --signature field:f.txt", "segmentation"),
    ];
    for (i, (args, kind)) in cases.iter().enumerate() {
        let dir = format!("c{i}");
        std::fs::create_dir_all(p.join(&dir)).unwrap();
        let (txt, png, wrl, toml) = (
            format!("{dir}/direct.txt"),
            format!("{dir}/direct.png"),
            format!("{dir}/direct.wrl"),
            format!("{dir}/files/exp.toml"),
        );
        let mut direct: Vec<&str> = args.split_whitespace().collect();
        direct.extend([
            "-o",
            &txt,
            "-o",
            &png,
            "-o",
            &wrl,
            "--size",
            "64",
            "--view",
            "20,10",
            "--save-experiment",
            &toml,
        ]);
        // A multi-column signature writes every column to .txt: the replay has the drawn
        // one, so its .txt is compared through the drawn column's picture and scene.
        let multi = args.split_whitespace().any(|a| a.starts_with("auto:"));
        ok_in(p, &direct);
        let text = std::fs::read_to_string(p.join(&toml)).unwrap();
        assert!(text.contains("experiment = \"field\""), "{text}");
        assert!(text.contains(&format!("kind = \"{kind}\"")), "{text}");
        assert!(text.contains("mesh_hash"), "{text}");
        let r1 = format!("{dir}/replay1");
        let r2 = format!("{dir}/replay2");
        ok_in(p, &["run", &toml, "-o", &r1]);
        ok_in(p, &["run", &toml, "-o", &r2]);
        for ext in ["png", "wrl", "txt"] {
            let replayed = p.join(&r1).join(format!("{kind}.{ext}"));
            if ext == "txt" && multi {
                continue;
            }
            same_bytes(&p.join(format!("{dir}/direct.{ext}")), &replayed);
        }
        for name in [
            format!("{kind}.png"),
            format!("{kind}.wrl"),
            format!("{kind}.txt"),
            "summary.json".into(),
        ] {
            same_bytes(&p.join(&r1).join(&name), &p.join(&r2).join(&name));
        }
        // The replay's summary names the request the command computed.
        let s: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(p.join(&r1).join("summary.json")).unwrap(),
        )
        .unwrap();
        assert_eq!(s["experiment"], "field");
        assert_eq!(s["request"]["kind"], *kind);
    }
}

#[test]
fn run_of_a_saved_field_file_reproduces_it_and_honours_basis_k() {
    // 40 pairs computed, the first 20 used: the field of the first 20 of 40 pairs.
    let file = "experiment = \"field\"\nmesh = \"sphere:res=2\"\nbasis_k = 40\n\n[figure]\nsize = 48\n\n[field]\nkind = \"distance\"\ndistance = \"commute\"\nk = 20\n";
    let d = folder_with("e.toml", file);
    let p = d.path();
    ok_in_with(p, "run e.toml -o a", &[]);
    ok_in_with(p, "run e.toml -o b", &[]);
    for name in [
        "distance.txt",
        "distance.png",
        "distance.wrl",
        "summary.json",
    ] {
        same_bytes(&p.join("a").join(name), &p.join("b").join(name));
    }
    let an = Analysis::new(build_str(SPHERE).unwrap(), AnalysisOptions::default());
    an.basis(40, &mut |_| {}, &spectral_mesh::CancelToken::new())
        .unwrap();
    let req = request(r#"{"kind": "distance", "distance": "commute", "k": 20}"#);
    let lib = an.field(&req).unwrap();
    assert_eq!(lib.basis_k, Some(40));
    assert_eq!(values(&p.join("a/distance.txt")), lib.values, "bit for bit");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p.join("a/summary.json")).unwrap()).unwrap();
    assert_eq!(s["basis"]["k"], 20);
    assert_eq!(s["basis"]["basis_k"], 40);
    assert_eq!(s["basis"]["eigenvalues"].as_array().unwrap().len(), 20);
}
