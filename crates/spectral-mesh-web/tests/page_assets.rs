//! What the page needs from the server: its 3D library embedded in the binary, and the
//! library's flat-field rule and truncation hint in the field header.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::net::SocketAddr;
use std::time::Duration;

use serde_json::{Value, json};
use spectral_mesh_web::api::assets_embedded;
use spectral_mesh_web::field::parse_reply;
use spectral_mesh_web::{ServeConfig, spawn};

#[path = "common/blocking.rs"]
mod blocking;

/// (status, headers in lower case, body) of one request.
fn http(
    addr: SocketAddr,
    method: &str,
    path: &str,
    body: Option<&Value>,
) -> (u16, String, Vec<u8>) {
    blocking::exchange(addr, method, path, body, Duration::from_secs(60))
}

fn server() -> spectral_mesh_web::RunningServer {
    spawn(ServeConfig {
        port: 0,
        ..ServeConfig::default()
    })
    .unwrap()
}

#[test]
fn the_3d_library_is_served_from_the_binary() {
    let srv = server();
    for path in ["/vendor/three.module.js", "/vendor/OrbitControls.js"] {
        let (status, head, body) = http(srv.addr, "GET", path, None);
        if assets_embedded() {
            assert_eq!(status, 200, "{path}");
            assert!(head.contains("x-spectral-mesh-asset: embedded"), "{head}");
            assert!(head.contains("text/javascript"), "{head}");
            assert!(body.len() > 1000, "{path}: {} bytes", body.len());
        } else {
            // Built without npm: a message that says how to get it.
            assert_eq!(status, 404, "{path}");
            assert!(String::from_utf8_lossy(&body).contains("npm"));
        }
    }
    // The page itself checks for its library before it starts.
    let (status, _, page) = http(srv.addr, "GET", "/", None);
    assert_eq!(status, 200);
    let page = String::from_utf8_lossy(&page);
    assert!(page.contains("lib-missing") && page.contains("/vendor/three.module.js"));
}

#[test]
fn a_heat_field_carries_the_flat_rule_and_the_truncation_hint() {
    let srv = server();
    let id = blocking::load_shape(srv.addr, "sphere:res=2");
    blocking::wait_for_basis(srv.addr, &id, 30, Duration::from_secs(60));
    let field = |t: f64| {
        let (status, _, b) = http(
            srv.addr,
            "POST",
            &format!("/api/mesh/{id}/field"),
            Some(&json!({"kind": "heat", "t": t, "k": 30, "levels": 0})),
        );
        assert_eq!(status, 200, "{}", String::from_utf8_lossy(&b));
        parse_reply(&b).unwrap()
    };
    // t = 1e12: constant up to rounding, one plateau, nothing critical.
    let flat = field(1e12);
    let cp = &flat.header["critical"];
    assert_eq!(cp["flat"], true, "{cp}");
    assert_eq!(
        (cp["minima"].as_u64(), cp["maxima"].as_u64()),
        (Some(0), Some(0))
    );
    assert_eq!(cp["saddles"].as_u64(), Some(0));
    assert!(flat.segments.is_empty());
    // A tiny t: the hint warns and suggests a larger k or t.
    let tiny = field(1e-4);
    let h = &tiny.header["truncation"];
    assert_eq!(h["k"], 30);
    assert_eq!(h["warning"], true, "{h}");
    assert!(h["t_needed"].as_f64().unwrap() > 1e-4);
    assert!(
        h["message"]
            .as_str()
            .unwrap()
            .contains("truncation dominates")
    );
    assert_eq!(tiny.header["critical"]["flat"], false);
    // No time, no hint.
    let (_, _, b) = http(
        srv.addr,
        "POST",
        &format!("/api/mesh/{id}/field"),
        Some(&json!({"kind": "distance", "distance": "biharmonic", "k": 30})),
    );
    assert!(parse_reply(&b).unwrap().header["truncation"].is_null());
}

/// The web face states no default of its own: `/api/defaults` is the library's object
/// (with the server's limits), the bodies' defaults and `Limits::default()` are the
/// library's, and the page's script and markup hold no literal default the server
/// defines (the page fills its controls from `/api/defaults`).
#[test]
fn the_web_faces_defaults_are_the_librarys() {
    use spectral_mesh::defaults::{self as d, server};
    let srv = server();
    let (status, _, body) = http(srv.addr, "GET", "/api/defaults", None);
    assert_eq!(status, 200);
    let got: Value = serde_json::from_slice(&body).unwrap();
    let mut want = spectral_mesh_render::defaults::to_json();
    want["limits"] = serde_json::to_value(spectral_mesh_web::Limits::default()).unwrap();
    assert_eq!(got, want);
    assert_eq!(got["analysis"]["normalize"], json!(d::NORMALIZE));
    assert_eq!(got["figure"]["levels"], json!(d::LEVELS));
    assert_eq!(got["requests"]["heat"]["t"], json!(d::DEFAULT_HEAT_T));

    // Bodies: what a key left out becomes.
    let f = spectral_mesh_web::body::parse_field(br#"{"kind": "heat"}"#).unwrap();
    assert_eq!((f.normalize, f.levels), (d::NORMALIZE, d::LEVELS));
    let b = spectral_mesh_web::body::parse_basis(b"").unwrap();
    assert_eq!(
        (b.normalize, b.k, b.laplacian),
        (d::NORMALIZE, d::DEFAULT_K, None)
    );
    let l = spectral_mesh_web::Limits::default();
    assert_eq!(
        (
            l.memory_bytes,
            l.cache_bytes,
            l.max_upload_bytes,
            l.max_json_bytes
        ),
        (
            server::MEMORY_MIB << 20,
            server::CACHE_MIB << 20,
            server::MAX_UPLOAD_MIB << 20,
            server::MAX_JSON_BYTES
        )
    );
    assert_eq!(
        (
            l.max_vertices,
            l.max_faces,
            l.max_k,
            l.max_jobs,
            l.max_queued,
            l.max_requests
        ),
        (
            server::MAX_VERTICES,
            server::MAX_FACES,
            server::MAX_K,
            server::MAX_JOBS,
            server::MAX_QUEUED,
            server::MAX_REQUESTS
        )
    );
    assert_eq!(
        (
            l.job_seconds,
            l.job_idle_seconds,
            l.request_seconds,
            l.idle_seconds
        ),
        (
            server::JOB_SECONDS,
            server::JOB_IDLE_SECONDS,
            server::REQUEST_SECONDS,
            server::IDLE_SECONDS
        )
    );
    let cfg = ServeConfig::default();
    assert_eq!((cfg.host, cfg.port), (server::HOST, server::PORT));

    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let read = |p: &str| std::fs::read_to_string(dir.join(p)).unwrap();
    // The body parser applies no literal default.
    let body_rs = read("src/body.rs");
    for pat in ["unwrap_or(", "map_or("] {
        for (i, line) in body_rs.lines().enumerate() {
            if let Some(p) = line.find(pat) {
                let arg = line[p + pat.len()..].trim_start();
                assert!(
                    !arg.starts_with(|c: char| c.is_ascii_digit())
                        && !arg.starts_with("true")
                        && !arg.starts_with("false"),
                    "src/body.rs:{}: a literal default: {}",
                    i + 1,
                    line.trim()
                );
            }
        }
    }
    // The page: its controls start empty and are filled from /api/defaults.
    let js = read("static/app.js");
    assert!(
        js.contains("'/api/defaults'"),
        "app.js does not read /api/defaults"
    );
    let keys = [
        "normalize",
        "k",
        "t",
        "levels",
        "persistence",
        "component",
        "laplacian",
    ];
    for (i, line) in js.lines().enumerate() {
        for key in keys {
            for sep in [": ", " = "] {
                let pat = format!("{key}{sep}");
                let mut rest = line;
                while let Some(p) = rest.find(&pat) {
                    let before = rest[..p].chars().last();
                    let value = rest[p + pat.len()..].trim_start();
                    rest = &rest[p + pat.len()..];
                    if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '.') {
                        continue;
                    }
                    let literal = value.starts_with(|c: char| c.is_ascii_digit())
                        || value.starts_with("true")
                        || value.starts_with("false")
                        || value.starts_with('\'') && key != "kind";
                    assert!(
                        !literal,
                        "static/app.js:{}: a literal default for `{key}` (read it from \
                         app.defaults, GET /api/defaults): {}",
                        i + 1,
                        line.trim()
                    );
                }
            }
        }
    }
    let html = read("static/index.html");
    for id in ["shape-spec", "k", "t", "levels", "persistence", "component"] {
        let tag_start = html
            .find(&format!("id=\"{id}\""))
            .unwrap_or_else(|| panic!("index.html has no #{id}"));
        let tag_end = tag_start + html[tag_start..].find('>').unwrap();
        let tag = &html[tag_start..tag_end];
        assert!(
            !tag.contains(" value="),
            "index.html: #{id} states a default ({tag}); app.js sets it from /api/defaults"
        );
    }
    let select = &html[html.find("id=\"laplacian\"").unwrap()..];
    let select = &select[..select.find("</select>").unwrap()];
    assert!(
        !select.contains("selected"),
        "index.html: the Laplacian select states a default; app.js sets it"
    );
}
