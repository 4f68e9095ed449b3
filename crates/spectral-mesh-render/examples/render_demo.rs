//! Renders a few demonstration pictures and times a large render.
//!
//! `cargo run --release -p spectral-mesh-render --example render_demo -- OUT_DIR`

#![allow(clippy::unwrap_used, clippy::expect_used)]

use spectral_mesh::Mesh;
use spectral_mesh_render::*;
use std::time::Instant;

/// Torus with `n × m` vertices (major radius 1, minor 0.4), z up.
fn torus(n: usize, m: usize) -> Mesh {
    let mut p = Vec::new();
    for i in 0..n {
        let u = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
        for j in 0..m {
            let v = 2.0 * std::f64::consts::PI * j as f64 / m as f64;
            let r = 1.0 + 0.4 * v.cos();
            p.push([r * u.cos(), r * u.sin(), 0.4 * v.sin()]);
        }
    }
    let id = |i: usize, j: usize| (i % n) * m + (j % m);
    let mut t = Vec::new();
    for i in 0..n {
        for j in 0..m {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    Mesh::new(p, t).expect("valid torus")
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).unwrap_or_else(|| ".".to_string());
    let mesh = torus(120, 48);
    let field: Vec<f64> = mesh.positions().iter().map(|p| p[0] + 0.5 * p[2]).collect();
    let mut scene = Scene::with_field(&mesh, &field, Colormap::Hue, None);
    let (lo, hi) = field_range(&field, Colormap::Hue);
    scene.level_sets = extract_level_sets(&mesh, &field, &level_values(lo, hi, 12));
    scene.markers = vec![
        Marker {
            position: mesh.positions()[0],
            kind: MarkerKind::Maximum,
        },
        Marker {
            position: mesh.positions()[60 * 48],
            kind: MarkerKind::Minimum,
        },
        Marker {
            position: mesh.positions()[30 * 48 + 12],
            kind: MarkerKind::Saddle,
        },
        Marker {
            position: mesh.positions()[90 * 48 + 12],
            kind: MarkerKind::Source,
        },
    ];
    for (name, view) in [
        ("iso", View::Iso),
        ("front", View::Front),
        ("top", View::Top),
    ] {
        let opts = RenderOptions {
            width: 640,
            height: 480,
            view,
            ..Default::default()
        };
        render_scene(&scene, &opts)?.save_png(format!("{out}/torus_{name}.png"))?;
    }
    for cmap in [Colormap::Viridis, Colormap::Turbo, Colormap::Diverging] {
        let mut s = Scene::with_field(&mesh, &field, cmap, None);
        s.level_sets = scene.level_sets.clone();
        let opts = RenderOptions {
            width: 480,
            height: 360,
            projection: Projection::Perspective { fov_deg: 35.0 },
            background: Background::Transparent,
            ..Default::default()
        };
        render_scene(&s, &opts)?.save_png(format!("{out}/torus_{cmap}.png"))?;
    }
    let mut f = std::fs::File::create(format!("{out}/torus.wrl"))?;
    write_vrml(&mut f, &scene)?;

    // Timing: ~100k triangles at 1024x1024.
    let big = torus(500, 100);
    let bf: Vec<f64> = big.positions().iter().map(|p| p[1]).collect();
    let mut bs = Scene::with_field(&big, &bf, Colormap::Turbo, None);
    bs.level_sets = extract_level_sets(&big, &bf, &level_values(-1.4, 1.4, 10));
    for ss in [1, 2, 3] {
        let opts = RenderOptions {
            width: 1024,
            height: 1024,
            supersample: ss,
            ..Default::default()
        };
        let t0 = Instant::now();
        let img = render_scene(&bs, &opts)?;
        let dt = t0.elapsed();
        println!(
            "{} triangles, 1024x1024, supersample {ss}: {:.1} ms",
            big.n_triangles(),
            dt.as_secs_f64() * 1e3
        );
        if ss == 3 {
            img.save_png(format!("{out}/big.png"))?;
        }
    }
    Ok(())
}
