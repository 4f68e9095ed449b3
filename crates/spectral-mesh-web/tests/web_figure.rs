//! One figure (issue 30): the field reply describes the figure as the render crate does
//! (colour stops, the one range rule, level values, markers, legend, colour bar),
//! `POST /api/figure` describes it again for other options, and a PNG download takes the
//! page's camera, size, height and print resolution.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::net::SocketAddr;
use std::time::Duration;

use serde_json::{Value, json};
use spectral_mesh_render::Colormap;
use spectral_mesh_render::description::stops;
use spectral_mesh_render::raster::colour_range;
use spectral_mesh_web::field::parse_reply;
use spectral_mesh_web::{ServeConfig, spawn};

#[path = "common/blocking.rs"]
mod blocking;

/// `POST /api/figure`: the figure of `summary` described again with `options`.
fn figure_again(addr: SocketAddr, summary: &Value, options: Value) -> (u16, Vec<u8>) {
    post(
        addr,
        "/api/figure",
        &json!({ "summary": summary, "options": options }),
    )
}

/// (status, body) of `POST path` with the JSON `body`.
fn post(addr: SocketAddr, path: &str, body: &Value) -> (u16, Vec<u8>) {
    let (s, _, b) = blocking::exchange(addr, "POST", path, Some(body), Duration::from_secs(120));
    (s, b)
}

#[test]
fn the_reply_describes_the_figure_and_the_download_uses_the_camera() {
    let srv = spawn(ServeConfig {
        port: 0,
        ..ServeConfig::default()
    })
    .unwrap();
    let id = blocking::load_shape(srv.addr, "sphere:res=2");
    // A harmonic map (no basis): values 0 and 1 at two constrained vertices.
    let req = json!({"kind": "harmonic", "constraints": 2, "colormap": "diverging", "levels": 6,
                     "segments": false});
    let (status, b) = post(srv.addr, &format!("/api/mesh/{id}/field"), &req);
    assert_eq!(status, 200, "{}", String::from_utf8_lossy(&b));
    let r = parse_reply(&b).unwrap();
    let h = &r.header;
    let fig = &h["figure"];
    let (min, max) = (h["min"].as_f64().unwrap(), h["max"].as_f64().unwrap());
    // The one range rule: diverging is symmetric about zero; levels over that range.
    let (lo, hi) = colour_range(min, max, Colormap::Diverging);
    assert_eq!(fig["range"], json!([lo, hi]));
    assert_eq!(fig["levels"].as_array().unwrap().len(), 6);
    assert!(r.segments.is_empty(), "segments were not asked for");
    let want: Vec<Value> = stops(Colormap::Diverging)
        .into_iter()
        .map(Value::from)
        .collect();
    assert_eq!(fig["stops"], Value::from(want));
    // Markers: the constraints are squares; the critical points as the header's.
    let marks = fig["marks"].as_array().unwrap();
    let of = |k: &str| {
        marks
            .iter()
            .find(|m| m["kind"] == k)
            .map_or(0, |m| m["vertices"].as_array().unwrap().len())
    };
    assert_eq!(of("constraint"), 2);
    assert_eq!(
        of("maximum") as u64,
        h["critical"]["maxima"].as_u64().unwrap()
    );
    let shapes: Vec<&str> = fig["marker_styles"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["shape"].as_str().unwrap())
        .collect();
    assert_eq!(
        shapes,
        ["star", "square", "triangle-up", "triangle-down", "diamond"]
    );
    assert_eq!(fig["colorbar"]["title"], "harmonic map value");
    // Described again for viridis and 4 levels, from the summary alone.
    let options = json!({"colormap": "viridis", "levels": 4});
    let (status, b) = figure_again(srv.addr, &fig["summary"], options);
    assert_eq!(status, 200, "{}", String::from_utf8_lossy(&b));
    let again: Value = serde_json::from_slice(&b).unwrap();
    assert_eq!(again["range"], json!([min, max]));
    assert_eq!(again["levels"].as_array().unwrap().len(), 4);
    assert!(
        again["colorbar"]["units"]
            .as_str()
            .unwrap()
            .contains("4 level sets, spacing")
    );
    let (status, b) = figure_again(srv.addr, &fig["summary"], json!({"colormap": "jet"}));
    assert_eq!(status, 400, "{}", String::from_utf8_lossy(&b));
    // The PNG of the page's camera at its canvas size, at 300 dpi.
    let mut dl = req.clone();
    dl["format"] = json!("png");
    dl["view"] = json!("camera:0.5,0.4,3.2,0,0,0,0,1,0,40");
    dl["size"] = json!(320);
    dl["height"] = json!(200);
    dl["scale"] = json!(1.0);
    dl["dpi"] = json!(300);
    let (status, png) = post(srv.addr, &format!("/api/mesh/{id}/download"), &dl);
    assert_eq!(status, 200, "{}", String::from_utf8_lossy(&png));
    let dec = png::Decoder::new(std::io::Cursor::new(png));
    let reader = dec.read_info().unwrap();
    let info = reader.info();
    assert_eq!((info.width, info.height), (320, 200));
    let dims = info.pixel_dims.unwrap();
    assert_eq!((dims.xppu, dims.unit), (11811, png::Unit::Meter));
    // A bad camera is refused, naming the key.
    dl["view"] = json!("camera:0,0,0,0,0,0,0,1,0,40");
    let (status, b) = post(srv.addr, &format!("/api/mesh/{id}/download"), &dl);
    assert_eq!(status, 400, "{}", String::from_utf8_lossy(&b));
    assert!(String::from_utf8_lossy(&b).contains("figure.view"));
}
