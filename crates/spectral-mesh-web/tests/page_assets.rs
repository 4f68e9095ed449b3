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
    let (status, _, body) = http(
        srv.addr,
        "POST",
        "/api/mesh",
        Some(&json!({"shape": "sphere:res=2"})),
    );
    assert_eq!(status, 200);
    let mesh: Value = serde_json::from_slice(&body).unwrap();
    let id = mesh["mesh_id"].as_str().unwrap().to_string();
    let (status, _, _) = http(
        srv.addr,
        "POST",
        &format!("/api/mesh/{id}/basis"),
        Some(&json!({"k": 30})),
    );
    assert!(status == 200 || status == 202);
    for _ in 0..600 {
        let (_, _, b) = http(
            srv.addr,
            "GET",
            &format!("/api/mesh/{id}/basis/status"),
            None,
        );
        let job: Value = serde_json::from_slice(&b).unwrap();
        if job["state"] == "done" {
            break;
        }
        assert!(job["state"] == "running", "{job}");
        std::thread::sleep(Duration::from_millis(100));
    }
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
