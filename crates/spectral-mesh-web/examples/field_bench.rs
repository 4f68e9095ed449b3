//! Server time of a field request, in-process and through HTTP, for the page's three
//! interactions: a new heat time t, a new source (anchor) and a new filter of the spectral
//! distance. Median of the repeats per interaction.
//!
//! `cargo run --release -p spectral-mesh-web --example field_bench -- [SHAPE] [K] [REPEATS]`
//! (defaults `torus:res=5` (100,352 vertices), 200, 15). The in-process part loads the
//! basis from `/tmp/field-bench-ID-K.npz` when it is there (else computes and saves it;
//! `FIELD_BENCH_COMPUTE=1` always computes it), and splits the critical points into their
//! classification and their persistence pairing; the HTTP part starts the server on
//! 127.0.0.1 and computes the basis through the API (`FIELD_BENCH_NO_HTTP=1` skips it).

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::net::SocketAddr;
use std::path::Path;
use std::time::{Duration, Instant};

use serde_json::{Value, json};
use spectral_mesh::analysis::{Analysis, AnalysisOptions, FieldRequest};
use spectral_mesh::cancel::CancelToken;
use spectral_mesh::fields::critical_points::{BoundaryRule, CriticalPointFinder};
use spectral_mesh::fields::persistence::{finite_for_critical, persistence};
use spectral_mesh::spectral::store::{BasisMeta, load_npz, save_npz};
use spectral_mesh_web::field::{field_reply, parse_reply};
use spectral_mesh_web::{ServeConfig, spawn};

/// The requests of one interaction, `i = 0..repeats`.
fn requests(what: &str, i: usize, n: usize, k: usize) -> Value {
    let filters = [
        "biharmonic",
        "commute",
        "diffusion:t=0.01",
        "mix:a=0.5,t=0.01",
    ];
    match what {
        "t slider (heat)" => {
            json!({"kind": "heat", "t": 0.001 * (1.0 + i as f64), "anchor": 0, "k": k})
        }
        "source click (heat)" => {
            json!({"kind": "heat", "t": 0.01, "anchor": (1 + i * 6007) % n, "k": k})
        }
        _ => json!({"kind": "distance", "distance": filters[i % 4], "source": 0, "k": k}),
    }
}

const WHAT: [&str; 3] = [
    "t slider (heat)",
    "source click (heat)",
    "filter switch (distance)",
];

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[path = "../tests/common/blocking.rs"]
mod blocking;

fn http(addr: SocketAddr, method: &str, path: &str, body: &Value) -> (u16, Vec<u8>) {
    let (status, _, body) =
        blocking::exchange(addr, method, path, Some(body), Duration::from_secs(3600));
    (status, body)
}

/// What `--help` prints.
const USAGE: &str = "field_bench [SHAPE] [K] [REPEATS]   (defaults torus:res=5 200 15)
  Server time of a field request at SHAPE with K eigenpairs: in-process (field, critical
  points, level sets, encoding; critical points split into classification and persistence
  pairing) and through HTTP on 127.0.0.1. Medians of REPEATS requests per interaction.
  FIELD_BENCH_COMPUTE=1: compute the basis even when /tmp/field-bench-ID-K.npz exists.
  FIELD_BENCH_NO_HTTP=1: in-process only.";

fn main() {
    if std::env::args().any(|a| a == "--help" || a == "-h") {
        println!("{USAGE}");
        return;
    }
    let (args, spec, k) = common::spec_and_k("torus:res=5", 200);
    let repeats: usize = args.get(2).map_or(15, |s| s.parse().unwrap());
    // A pool of its own, made first, as the server's field threads (see AppState::fields).
    let pool = rayon::ThreadPoolBuilder::new().build().unwrap();
    let mesh = spectral_mesh::shapes::build_str(&spec).unwrap();
    let n = mesh.n_vertices();
    println!("{spec}: n = {n}, k = {k}, {repeats} requests per interaction, levels = 10");

    // In-process: the analysis and the reply code the server runs, without HTTP.
    let an = Analysis::new(mesh.clone(), AnalysisOptions::default());
    let cache = format!("/tmp/field-bench-{}-{k}.npz", &mesh.content_hash()[..16]);
    if Path::new(&cache).exists() && std::env::var_os("FIELD_BENCH_COMPUTE").is_none() {
        an.set_basis(load_npz(Path::new(&cache)).unwrap().0)
            .unwrap();
    } else {
        let t = Instant::now();
        let b = an.basis(k, &mut |_| {}, &CancelToken::new()).unwrap();
        println!(
            "basis: {:.1} s (saved to {cache})",
            t.elapsed().as_secs_f64()
        );
        let meta = BasisMeta::new(&b, Some(&mesh), &Default::default());
        save_npz(&b, Path::new(&cache), &meta).unwrap();
    }
    // The page's figure options: 10 level sets (whose segments the reply carries).
    let opts = spectral_mesh_render::figure::FigureOptions {
        levels: 10,
        ..Default::default()
    };
    // First use builds the connectivity and the link edges (once per analysis).
    let req: FieldRequest = serde_json::from_value(requests(WHAT[0], 0, n, k)).unwrap();
    let t = Instant::now();
    field_reply(&an, &req, &opts, true).unwrap().unwrap();
    println!(
        "first field of the analysis (builds connectivity and link edges): {:.1} ms",
        t.elapsed().as_secs_f64() * 1e3
    );
    println!(
        "\nin-process, medians in ms: | interaction | field | critical points | level sets | encode | total |"
    );
    // The interactions take turns, so that the load of the moment falls on all three.
    let mut cols: Vec<[Vec<f64>; 5]> = WHAT.iter().map(|_| Default::default()).collect();
    // The critical points again, outside the timed reply: classification, pairing; and
    // the counts (raw and shown: minima, saddles, maxima) of the last request.
    let finder = CriticalPointFinder::new(&mesh);
    let mut parts: Vec<[Vec<f64>; 2]> = WHAT.iter().map(|_| Default::default()).collect();
    let mut counts = vec![String::new(); WHAT.len()];
    for i in 0..repeats {
        for (w, what) in WHAT.iter().enumerate() {
            let req: FieldRequest = serde_json::from_value(requests(what, i, n, k)).unwrap();
            let t = Instant::now();
            let (r, bytes) = pool.install(|| {
                let r = field_reply(&an, &req, &opts, true).unwrap().unwrap();
                let bytes = r.to_bytes().unwrap();
                (r, bytes)
            });
            let total = t.elapsed().as_secs_f64() * 1e3;
            std::hint::black_box(&bytes);
            let tm = r.header.timing_ms;
            let c = &mut cols[w];
            c[0].push(tm.field);
            c[1].push(tm.critical);
            c[2].push(tm.levels);
            c[3].push(total - tm.total);
            c[4].push(total);
            let values = finite_for_critical(&r.field.values);
            let (raw, classify_ms, pairing_ms, p) = pool.install(|| {
                let t = Instant::now();
                let raw = finder.find(&values, BoundaryRule::default()).unwrap();
                let classify_ms = t.elapsed().as_secs_f64() * 1e3;
                let t = Instant::now();
                let p = persistence(&finder, &values, raw.clone()).unwrap();
                (raw, classify_ms, t.elapsed().as_secs_f64() * 1e3, p)
            });
            parts[w][0].push(classify_ms);
            parts[w][1].push(pairing_ms);
            let count = |c: &spectral_mesh::fields::critical_points::CriticalPoints| {
                format!("{}/{}/{}", c.minima.len(), c.saddle_count(), c.maxima.len())
            };
            counts[w] = format!("{} | {}", count(&raw), count(&p.shown));
        }
    }
    for (what, c) in WHAT.iter().zip(cols) {
        let m: Vec<String> = c.into_iter().map(|c| format!("{:.1}", median(c))).collect();
        println!("| {what} | {} |", m.join(" | "));
    }
    println!(
        "\ncritical points in-process, medians in ms: | interaction | classification | persistence pairing | raw min/saddles/max (last) | shown |"
    );
    for ((what, c), counts) in WHAT.iter().zip(parts).zip(&counts) {
        let m: Vec<String> = c.into_iter().map(|c| format!("{:.2}", median(c))).collect();
        println!("| {what} | {} | {counts} |", m.join(" | "));
    }
    drop(an);
    if std::env::var_os("FIELD_BENCH_NO_HTTP").is_some() {
        return;
    }

    // Through HTTP: the server on 127.0.0.1, the basis computed through the API.
    let server = spawn(ServeConfig {
        port: 0,
        limits: spectral_mesh_web::Limits {
            cache_bytes: 2 << 30,
            memory_bytes: 3 << 30,
            ..Default::default()
        },
        ..Default::default()
    })
    .unwrap();
    let addr = server.addr;
    let id = blocking::load_shape(addr, &spec);
    let t = Instant::now();
    blocking::wait_for_basis(addr, &id, k, Duration::from_secs(24 * 3600));
    println!(
        "\nbasis through the API: {:.1} s",
        t.elapsed().as_secs_f64()
    );
    let path = format!("/api/mesh/{id}/field");
    let (_, b) = http(addr, "POST", &path, &requests(WHAT[0], 0, n, k));
    parse_reply(&b).unwrap();
    println!(
        "through HTTP, medians in ms: | interaction | round trip | server total | field | critical points | level sets | reply bytes |"
    );
    // (round trip, server total, field, critical points, level sets), bytes.
    let mut cols: Vec<[Vec<f64>; 5]> = WHAT.iter().map(|_| Default::default()).collect();
    let mut sizes = [0usize; 3];
    for i in 0..repeats {
        for (w, what) in WHAT.iter().enumerate() {
            let body = requests(what, i, n, k);
            let t = Instant::now();
            let (status, b) = http(addr, "POST", &path, &body);
            let rt = t.elapsed().as_secs_f64() * 1e3;
            assert_eq!(status, 200, "{}", String::from_utf8_lossy(&b));
            let r = parse_reply(&b).unwrap();
            let tm = &r.header["timing_ms"];
            let c = &mut cols[w];
            c[0].push(rt);
            for (j, key) in ["total", "field", "critical", "levels"].iter().enumerate() {
                c[j + 1].push(tm[key].as_f64().unwrap());
            }
            sizes[w] = b.len();
        }
    }
    for ((what, c), size) in WHAT.iter().zip(cols).zip(sizes) {
        let m: Vec<String> = c.into_iter().map(|c| format!("{:.1}", median(c))).collect();
        println!("| {what} | {} | {size} |", m.join(" | "));
    }
}
