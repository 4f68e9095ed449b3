//! Point clouds in the web app, over real TCP on 127.0.0.1: an uploaded point file is
//! analysed with its point-cloud Laplacian, and every field the server gives is the
//! library's own (`Analysis::from_input` on the same bytes) to 1e-12; every limit applies
//! to clouds as to meshes; a discretization that needs triangles is refused with a reason.
//! Also: shape specs are refused above the vertex limit before they are built.
//!
//! The real clouds are the shared ones (`spectral_mesh_testkit::shared_points`, beside
//! `SPECTRAL_MESH_SHARED_MESHES`); without them that part says it was skipped (it fails
//! under CI).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::net::SocketAddr;
use std::time::{Duration, Instant};

use serde_json::json;
use spectral_mesh::Laplacian;
use spectral_mesh::analysis::{Analysis, AnalysisOptions, FieldRequest};
use spectral_mesh::io::read_input_from_bytes;
use spectral_mesh_web::Limits;
use spectral_mesh_web::field::parse_reply;

mod common;
use common::*;

/// `n` points on the unit sphere (Fibonacci lattice) as `.xyz` text.
fn sphere_xyz(n: usize) -> Vec<u8> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let mut s = String::from("# a generated sphere\n");
    for i in 0..n {
        let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
        let r = (1.0 - y * y).sqrt();
        let th = golden * i as f64;
        s += &format!("{:.12} {:.12} {:.12}\n", r * th.cos(), y, r * th.sin());
    }
    s.into_bytes()
}

/// Uploads `bytes` as `name`, checks the reply says point cloud, asks a basis of `k`
/// pairs (the default Laplacian: robust for a cloud) and a heat field, and compares the
/// basis' largest eigenvalue and the field (the full-precision text download) with the
/// library's analysis of the same bytes, to 1e-12.
async fn cloud_matches_the_library(addr: SocketAddr, name: &str, bytes: &[u8], k: usize) {
    let r = upload(addr, name, bytes).await;
    assert_eq!(r.status, 200, "{name}: {}", r.text());
    let m = r.json();
    assert_eq!(m["kind"], "point cloud", "{m}");
    assert_eq!(m["m"], 0);
    assert_eq!(m["laplacians"], json!(["robust"]));
    let id = m["mesh_id"].as_str().unwrap().to_string();
    let n = m["n"].as_u64().unwrap() as usize;

    let input = read_input_from_bytes(bytes, name).unwrap();
    assert!(matches!(input, spectral_mesh::io::Input::Points(_)));
    let an = Analysis::from_input(
        input,
        AnalysisOptions {
            laplacian: Laplacian::Robust,
            normalize: true,
            ..AnalysisOptions::default()
        },
    )
    .unwrap();
    assert_eq!(an.n(), n);
    let spacing = an.point_spacing().unwrap();
    assert_eq!(m["point_spacing"].as_f64().unwrap(), spacing, "{name}");
    // The page sizes its splats as the pictures do, with the renderer's factor.
    assert_eq!(
        m["point_radius_factor"].as_f64().unwrap(),
        spectral_mesh_render::figure::POINT_RADIUS_FACTOR,
        "{name}"
    );
    assert_eq!(
        m["info"]["union_triangles"].as_u64().unwrap() as usize,
        an.mesh().n_triangles()
    );
    assert_eq!(
        m["info"]["components"].as_u64().unwrap() as usize,
        an.topology().n_components()
    );
    // The geometry: the points, no triangles.
    let g = get(addr, &format!("/api/mesh/{id}/geometry")).await;
    assert_eq!(g.status, 200);
    assert_eq!(g.body.len(), 8 + 12 * n);
    assert_eq!(u32::from_le_bytes(g.body[4..8].try_into().unwrap()), 0);

    let r = post_json(addr, &format!("/api/mesh/{id}/basis"), json!({"k": k})).await;
    assert!(r.status == 200 || r.status == 202, "{name}: {}", r.text());
    let st = wait_job(addr, &id).await;
    assert_eq!(st["state"], "done", "{name}: {st}");
    assert_eq!(st["laplacian"], "robust");

    let body = json!({"kind": "heat", "t": 0.02, "k": k});
    let req: FieldRequest = serde_json::from_value(body.clone()).unwrap();
    let lib = an.field(&req).unwrap();
    let basis = an.held_basis().unwrap();
    let r = post_json(addr, &format!("/api/mesh/{id}/field"), body.clone()).await;
    assert_eq!(r.status, 200, "{name}: {}", r.text());
    let f = parse_reply(&r.body).unwrap();
    let h = &f.header;
    assert_eq!(h["point_cloud"], true);
    assert_eq!(h["laplacian"], "robust");
    assert_eq!(h["point_spacing"].as_f64().unwrap(), spacing);
    assert_eq!(h["k"], k);
    let lmax = h["lambda_max"].as_f64().unwrap();
    let want = basis.values[k - 1];
    assert!(
        (lmax - want).abs() <= 1e-12 * want.abs().max(1.0),
        "{name}: lambda_{k} {lmax} vs the library's {want}"
    );
    assert_eq!(f.values.len(), n);
    // The server's numbers at full precision (the text download) against the library's.
    let mut dl = body.clone();
    dl["format"] = json!("txt");
    let r = post_download(addr, &id, dl).await;
    assert_eq!(r.status, 200, "{name}: {}", r.text());
    let txt: Vec<f64> = r.text().lines().map(|l| l.parse().unwrap()).collect();
    assert_eq!(txt.len(), n);
    assert_eq!(lib.values.len(), n);
    assert_close(&txt, &lib.values, 1e-12, &format!("{name} point"));
    for i in 0..n {
        assert_eq!(f.values[i], lib.values[i] as f32, "{name} point {i}");
    }
    // A field asking for level sets gets the library's, on the triangle union.
    let r = post_field(
        addr,
        &id,
        json!({"kind": "heat", "t": 0.02, "k": k, "levels": 5}),
    )
    .await;
    let f = parse_reply(&r.body).unwrap();
    assert_eq!(f.header["levels"].as_array().unwrap().len(), 5);
    assert!(!f.segments.is_empty(), "{name}: no level-set segment");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn uploaded_clouds_give_the_librarys_fields() {
    let addr = start(Limits::default()).await;
    // A generated one: always.
    cloud_matches_the_library(addr, "sphere600.xyz", &sphere_xyz(600), 12).await;
    // Real ones (a text scan with normals, a binary vertex-only PLY).
    if let Some(dir) = spectral_mesh_testkit::shared_points() {
        for (file, k) in [("kitten.xyz", 20), ("oni.ply", 20)] {
            let bytes = std::fs::read(dir.join(file)).unwrap();
            cloud_matches_the_library(addr, file, &bytes, k).await;
        }
    }
    // A cloud's picture and files: a PNG, a PLY point set, the experiment file.
    let r = upload(addr, "sphere600.xyz", &sphere_xyz(600)).await;
    let id = r.json()["mesh_id"].as_str().unwrap().to_string();
    let body = json!({"kind": "heat", "t": 0.02, "k": 12});
    let mut png = body.clone();
    png["format"] = json!("png");
    png["size"] = json!(64);
    let r = post_download(addr, &id, png).await;
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(&r.body[..4], b"\x89PNG");
    let mut ply = body.clone();
    ply["format"] = json!("ply");
    let r = post_download(addr, &id, ply).await;
    assert_eq!(r.status, 200, "{}", r.text());
    let head = String::from_utf8_lossy(&r.body[..r.body.len().min(400)]).into_owned();
    assert!(
        head.starts_with("ply") && head.contains("element vertex 600"),
        "{head}"
    );
    assert!(!head.contains("element face 1"), "a point set: {head}");
    let mut toml = body.clone();
    toml["format"] = json!("toml");
    let r = post_download(addr, &id, toml).await;
    let t = r.text();
    assert!(
        t.contains("mesh = \"sphere600.xyz\"") && t.contains("laplacian = \"robust\""),
        "{t}"
    );
    // The cloud's Laplacian parameters are recorded, so a replay does not depend on the
    // defaults of the day.
    let f = spectral_mesh::experiments::file::ExperimentFile::parse(&t, "export.toml").unwrap();
    assert!(t.contains("[point_cloud]"), "{t}");
    assert_eq!(
        f.point_cloud_params(),
        spectral_mesh::operators::PointCloudParams::default()
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn clouds_obey_the_limits_and_refuse_triangle_laplacians() {
    let addr = start(Limits {
        max_vertices: 500,
        max_upload_bytes: 64 << 10,
        max_k: 40,
        ..Limits::default()
    })
    .await;
    // More points than the vertex limit: 413 naming the figure and the option.
    let r = upload(addr, "big.xyz", &sphere_xyz(800)).await;
    assert_refused(&r, 413, &["800 points", "--max-vertices"]);
    // More bytes than the upload limit.
    let r = upload(addr, "huge.xyz", &sphere_xyz(3000)).await;
    assert_refused(&r, 413, &["--max-upload-mib"]);
    // Collinear points: no triangle, refused at the upload with the reason.
    let line: String = (0..20).map(|i| format!("{i} 0 0\n")).collect();
    let r = upload(addr, "line.xyz", line.as_bytes()).await;
    assert_refused(&r, 422, &["line.xyz", "collinear"]);

    let r = upload(addr, "small.xyz", &sphere_xyz(30)).await;
    assert_eq!(r.status, 200, "{}", r.text());
    let id = r.json()["mesh_id"].as_str().unwrap().to_string();
    let basis = format!("/api/mesh/{id}/basis");
    // k beyond the points, beyond --max-k (the same rules as a mesh).
    let r = post_json(addr, &basis, json!({"k": 31})).await;
    assert_refused(&r, 422, &["1..=30", "points"]);
    // A discretization that needs triangles: refused, saying why and what applies.
    for lap in ["fem", "cot", "uniform"] {
        let r = post_json(addr, &basis, json!({"k": 5, "laplacian": lap})).await;
        assert_eq!(r.status, 422, "{lap}: {}", r.text());
        let e = r.error();
        assert!(
            e.starts_with("laplacian:")
                && e.contains("point cloud")
                && e.contains("triangles")
                && e.contains("robust"),
            "{e}"
        );
        let r = post_field(addr, &id, json!({"kind": "heat", "k": 5, "laplacian": lap})).await;
        assert_eq!(r.status, 422, "{lap}: {}", r.text());
    }
    // Robust, given or not, works; k = n is allowed as for a mesh.
    let r = post_json(addr, &basis, json!({"k": 30, "laplacian": "robust"})).await;
    assert!(r.status == 200 || r.status == 202, "{}", r.text());
    assert_eq!(wait_job(addr, &id).await["state"], "done");
    let r = post_field(addr, &id, json!({"kind": "heat", "k": 30})).await;
    assert_eq!(r.status, 200, "{}", r.text());
    // A harmonic map needs no basis: the library's preset constraints on the cloud.
    let r = post_field(addr, &id, json!({"kind": "harmonic"})).await;
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(
        parse_reply(&r.body).unwrap().header["constraints"]
            .as_array()
            .unwrap()
            .len(),
        2
    );
    assert_eq!(get(addr, "/api/health").await.json()["ok"], true);
}

/// A shape spec above the vertex limit is refused from its size, without being built: the
/// largest valid spec (`torus:res=8`, 6.4 million vertices, gigabytes and tens of seconds to
/// build) answers at once; a resolution beyond the shape's range (`sphere:res=12`, about
/// 1.7 x 10^8 vertices) is refused by the spec's own check.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn oversized_shape_specs_are_refused_before_they_are_built() {
    let addr = start(Limits::default()).await;
    for (spec, status, words) in [
        (
            "torus:res=8",
            413,
            &["6422528 vertices", "1000000", "--max-vertices"][..],
        ),
        (
            "irregular-torus:res=8",
            413,
            &["vertices", "--max-vertices"][..],
        ),
        ("sphere:res=12", 400, &["res", "at most 9"][..]),
    ] {
        let t = Instant::now();
        let r = post_json(addr, "/api/mesh", json!({ "shape": spec })).await;
        let took = t.elapsed();
        assert_eq!(r.status, status, "{spec}: {}", r.text());
        for w in words {
            assert!(r.error().contains(w), "{spec}: {}", r.error());
        }
        // Not built: building it would take tens of seconds (a behaviour bound, not a
        // speed figure).
        assert!(took < Duration::from_secs(10), "{spec} took {took:?}");
    }
    let h = get(addr, "/api/health").await.json();
    assert_eq!(h["cache_entries"], 0, "{h}");
    // Within the limit, a shape is built as before.
    let r = post_json(addr, "/api/mesh", json!({"shape": "torus:res=2"})).await;
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.json()["kind"], "mesh");
    assert_eq!(r.json()["laplacians"].as_array().unwrap().len(), 6);
}
