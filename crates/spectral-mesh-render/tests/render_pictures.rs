//! Property tests of the renderer, the VRML writer and the plots.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use spectral_mesh::Mesh;
use spectral_mesh_render::vrml::parse_vrml;
use spectral_mesh_render::*;

/// UV sphere of radius `r` centred at the origin, poles on the z axis.
fn sphere(r: f64, rings: usize, segs: usize) -> Mesh {
    let mut p = vec![[0.0, 0.0, r]];
    for i in 1..rings {
        let th = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..segs {
            let ph = 2.0 * std::f64::consts::PI * (j as f64 + 0.5 * (i % 2) as f64) / segs as f64;
            p.push([
                r * th.sin() * ph.cos(),
                r * th.sin() * ph.sin(),
                r * th.cos(),
            ]);
        }
    }
    p.push([0.0, 0.0, -r]);
    let south = p.len() - 1;
    let ring = |i: usize, j: usize| 1 + (i - 1) * segs + (j % segs);
    // The caps (fans around the poles), then two triangles per quad of the bands.
    let mut t: Vec<[usize; 3]> = (0..segs)
        .flat_map(|j| {
            let (a, b) = (ring(rings - 1, j), ring(rings - 1, j + 1));
            [[0, ring(1, j), ring(1, j + 1)], [south, b, a]]
        })
        .collect();
    for i in 1..rings - 1 {
        for j in 0..segs {
            let (a, d) = (ring(i, j), ring(i, j + 1)); // on ring i
            let (b, c) = (ring(i + 1, j), ring(i + 1, j + 1)); // on ring i + 1
            t.extend([[a, b, c], [a, c, d]]);
        }
    }
    Mesh::new(p, t).unwrap()
}

fn marker(position: [f64; 3], kind: MarkerKind) -> Marker {
    Marker { position, kind }
}

/// Square `[-1, 1]^2` in the plane z = 0, `n × n` cells.
fn quad(n: usize) -> Mesh {
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            p.push([
                -1.0 + 2.0 * i as f64 / n as f64,
                -1.0 + 2.0 * j as f64 / n as f64,
                0.0,
            ]);
        }
    }
    // Each cell (a = its lower-left corner) split along the diagonal a, a + n + 2.
    let t: Vec<[usize; 3]> = (0..n)
        .flat_map(|j| (0..n).map(move |i| j * (n + 1) + i))
        .flat_map(|a| [[a, a + 1, a + n + 2], [a, a + n + 2, a + n + 1]])
        .collect();
    Mesh::new(p, t).unwrap()
}

/// The opaque pixels of `img` with a red channel under 100 (lines drawn dark).
fn dark_pixels(img: &spectral_mesh_render::Image) -> usize {
    img.rgba
        .chunks_exact(4)
        .filter(|c| c[0] < 100 && c[3] == 255)
        .count()
}

/// Lines and markers at their screen size (scale 1) whatever the picture's size.
fn opts(w: u32, h: u32) -> RenderOptions {
    RenderOptions {
        width: w,
        height: h,
        view: View::Front,
        supersample: 2,
        scale: 1.0,
        ..RenderOptions::default()
    }
}

fn px(img: &Image, x: f64, y: f64) -> [u8; 4] {
    img.pixel(x as u32, y as u32).unwrap()
}

fn is_white(c: [u8; 4]) -> bool {
    c == [255, 255, 255, 255]
}

fn is_dark(c: [u8; 4]) -> bool {
    c[0] < 45 && c[1] < 45 && c[2] < 45 && c[3] == 255
}

#[test]
fn sphere_fills_the_expected_disc() {
    let mesh = sphere(1.0, 48, 96);
    for bg in [Background::White, Background::Transparent] {
        let o = RenderOptions {
            background: bg,
            ..opts(200, 160)
        };
        let img = render_scene(&Scene::new(&mesh), &o).unwrap();
        assert_eq!((img.width, img.height), (200, 160));
        // Bounding-sphere radius 1 fitted in min(200,160)/2 * (1 - 2 * 0.04) = 73.6 px.
        let (cx, cy, r) = (100.0, 80.0, 73.6);
        let mut inside = 0;
        for y in 0..img.height {
            for x in 0..img.width {
                let d = ((x as f64 + 0.5 - cx).powi(2) + (y as f64 + 0.5 - cy).powi(2)).sqrt();
                let c = img.pixel(x, y).unwrap();
                if d < r - 3.0 {
                    inside += 1;
                    assert_eq!(c[3], 255, "({x},{y}) should be opaque");
                    assert!(!is_white(c), "({x},{y}) should be covered");
                } else if d > r + 1.5 {
                    match bg {
                        Background::Transparent => assert_eq!(c[3], 0, "({x},{y})"),
                        _ => assert!(is_white(c), "({x},{y}) should be background"),
                    }
                }
            }
        }
        assert!(inside > 15000);
    }
}

#[test]
fn lighting_is_brighter_facing_the_light_and_two_sided() {
    // An open hemisphere (z >= 0 half) seen from behind still gets lit (two-sided).
    let mesh = sphere(1.0, 24, 48);
    let img = render_scene(&Scene::new(&mesh), &opts(120, 120)).unwrap();
    // The light comes from the upper left front: upper-left is brighter than lower-right.
    let ul = px(&img, 40.0, 40.0);
    let lr = px(&img, 80.0, 80.0);
    assert!(ul[0] > lr[0], "{ul:?} vs {lr:?}");
    let (p, t) = mesh.clone().into_parts();
    let keep: Vec<[usize; 3]> = t
        .into_iter()
        .filter(|tri| tri.iter().all(|&v| p[v][2] >= -1e-9))
        .collect();
    let half = Mesh::new(p, keep).unwrap();
    let back = RenderOptions {
        view: View::Angles {
            azimuth_deg: 180.0,
            elevation_deg: 0.0,
        },
        ambient: 0.0,
        diffuse: 1.0,
        ..opts(120, 120)
    };
    let img = render_scene(&Scene::new(&half), &back).unwrap();
    let c = px(&img, 60.0, 60.0);
    assert!(c[0] > 100, "inside of the shell is lit: {c:?}");
}

#[test]
fn flat_quad_shows_the_hue_of_the_field() {
    let mesh = quad(40);
    let field: Vec<f64> = mesh.positions().iter().map(|p| p[0]).collect();
    let scene = {
        let mut s = Scene::new(&mesh);
        s.vertex_colors = field_colors(&field, Colormap::Hue, None);
        s
    };
    let o = RenderOptions {
        ambient: 1.0,
        diffuse: 0.0,
        ..opts(300, 300)
    };
    let img = render_scene(&scene, &o).unwrap();
    let cam = scene.camera(&o);
    // Sample along the middle row; invert the orthographic projection for x.
    let y = cam.cy;
    for k in 1..20 {
        let xw = -0.95 + 1.9 * k as f64 / 20.0;
        let [sx, sy, _] = cam.project([xw, 0.0, 0.0]);
        assert!((sy - y).abs() < 1e-9);
        let c = px(&img, sx, sy);
        // The pixel centre's world x.
        let xc = (sx.floor() + 0.5 - cam.cx) / cam.scale;
        let want = Colormap::Hue.map((xc + 1.0) / 2.0);
        for i in 0..3 {
            assert!(
                (c[i] as i32 - want[i] as i32).abs() <= 10,
                "x {xc}: got {c:?}, want {want:?}"
            );
        }
    }
    // Known vertices: left edge red, right edge magenta.
    let [lx, ly, _] = cam.project([-0.98, 0.0, 0.0]);
    let [rx, ry, _] = cam.project([0.98, 0.0, 0.0]);
    let l = px(&img, lx, ly);
    let r = px(&img, rx, ry);
    assert!(l[0] > 240 && l[1] < 20 && l[2] < 20, "{l:?}");
    assert!(r[0] > 220 && r[1] < 20 && r[2] > 220, "{r:?}");
}

#[test]
fn level_set_lines_are_dark_where_expected() {
    let mesh = quad(20);
    let field: Vec<f64> = mesh.positions().iter().map(|p| p[0]).collect();
    let mut scene = Scene::with_field(&mesh, &field, Colormap::Viridis, None);
    scene.colorbar = None;
    scene.level_sets = extract_level_sets(&mesh, &field, &[0.013, 0.5]);
    let o = RenderOptions {
        line_width: 2.0,
        ..opts(200, 200)
    };
    let img = render_scene(&scene, &o).unwrap();
    let cam = scene.camera(&o);
    for yw in [-0.8, -0.3, 0.2, 0.7] {
        for xw in [0.013, 0.5] {
            let [x, y, _] = cam.project([xw, yw, 0.0]);
            assert!(is_dark(px(&img, x, y)), "line at x = {xw}, y = {yw}");
        }
        for xw in [-0.5, 0.25, 0.8] {
            let [x, y, _] = cam.project([xw, yw, 0.0]);
            assert!(!is_dark(px(&img, x, y)), "no line at x = {xw}");
        }
    }
}

#[test]
fn hidden_level_sets_are_occluded() {
    let mesh = sphere(1.0, 48, 96);
    let field: Vec<f64> = mesh.positions().iter().map(|p| p[2]).collect();
    let o = RenderOptions {
        line_width: 2.0,
        ..opts(240, 240)
    };
    // z = +0.5 faces the camera (front view looks down -z); z = -0.5 is behind, on the
    // same projected circle of radius sqrt(0.75).
    for (value, visible) in [(0.5, true), (-0.5, false)] {
        let mut scene = Scene::new(&mesh);
        scene.level_sets = extract_level_sets(&mesh, &field, &[value]);
        let img = render_scene(&scene, &o).unwrap();
        let cam = scene.camera(&o);
        let rr = 0.75f64.sqrt();
        let mut dark = 0;
        let n = 72;
        for k in 0..n {
            let a = 2.0 * std::f64::consts::PI * (k as f64 + 0.5) / n as f64;
            let [x, y, _] = cam.project([rr * a.cos(), rr * a.sin(), value]);
            if is_dark(px(&img, x, y)) {
                dark += 1;
            }
        }
        if visible {
            assert!(dark >= n * 9 / 10, "visible ring: {dark}/{n} dark");
        } else {
            assert_eq!(dark, 0, "hidden ring must not show");
        }
    }
}

#[test]
fn hidden_lines_do_not_leak_past_the_silhouette() {
    // A level set just behind the silhouette circle of a sphere seen from the front.
    let mesh = sphere(1.0, 64, 128);
    let field: Vec<f64> = mesh.positions().iter().map(|p| p[2]).collect();
    let mut scene = Scene::new(&mesh);
    scene.vertex_colors = vec![[1.0, 1.0, 1.0]; mesh.n_vertices()];
    scene.level_sets = extract_level_sets(&mesh, &field, &[-0.06]);
    let o = RenderOptions {
        line_width: 4.0,
        ambient: 1.0,
        diffuse: 0.0,
        ..opts(200, 200)
    };
    let img = render_scene(&scene, &o).unwrap();
    let dark = dark_pixels(&img);
    assert_eq!(dark, 0, "hidden ring leaked {dark} dark pixels");
    // The same ring just in front of the silhouette is drawn.
    scene.level_sets = extract_level_sets(&mesh, &field, &[0.06]);
    let img = render_scene(&scene, &o).unwrap();
    let dark = dark_pixels(&img);
    assert!(dark > 300, "{dark}");
}

#[test]
fn markers_appear_at_projected_positions_when_visible() {
    let mesh = sphere(1.0, 32, 64);
    let mut scene = Scene::new(&mesh);
    let s = 0.6f64;
    let front = [s, 0.0, (1.0 - s * s).sqrt()];
    scene.markers = vec![
        marker([0.0, 0.0, 1.0], MarkerKind::Maximum),
        marker([0.0, 0.0, -1.0], MarkerKind::Minimum),
        marker(front, MarkerKind::Saddle),
        marker([-0.6, 0.0, 0.8], MarkerKind::Source),
    ];
    let o = RenderOptions {
        scale: 2.0,
        ..opts(300, 300)
    };
    let img = render_scene(&scene, &o).unwrap();
    let cam = scene.camera(&o);
    let at = |p: [f64; 3]| {
        let [x, y, _] = cam.project(p);
        px(&img, x, y)
    };
    let close = |a: [u8; 4], b: [u8; 3]| (0..3).all(|i| (a[i] as i32 - b[i] as i32).abs() <= 12);
    assert!(close(at([0.0, 0.0, 1.0]), MarkerKind::Maximum.color()));
    assert!(close(at(front), MarkerKind::Saddle.color()));
    assert!(close(at([-0.6, 0.0, 0.8]), MarkerKind::Source.color()));
    // The hidden minimum (behind the sphere, same projection as the maximum) is not drawn.
    let blue = MarkerKind::Minimum.color();
    let any_blue = img
        .rgba
        .chunks_exact(4)
        .any(|c| close([c[0], c[1], c[2], c[3]], blue));
    assert!(!any_blue);
    // Shapes: the saddle is a diamond (its box's corners are not filled, its edge
    // midpoints are); the maximum a triangle pointing up (filled just above its base's
    // ends, not at its top corners).
    let [x, y, _] = cam.project(front);
    let h = 0.5 * MarkerKind::Saddle.size() * 2.0;
    let green = MarkerKind::Saddle.color();
    assert!(!close(px(&img, x + 0.8 * h, y + 0.8 * h), green));
    assert!(close(px(&img, x + 0.5 * h, y), green));
    let [x, y, _] = cam.project([0.0, 0.0, 1.0]);
    let h = 0.5 * MarkerKind::Maximum.size() * 2.0;
    let red = MarkerKind::Maximum.color();
    assert!(close(px(&img, x - 0.45 * h, y + 0.45 * h), red));
    assert!(!close(px(&img, x - 0.6 * h, y - 0.6 * h), red));
}

/// A camera given by eye, target and up: the target is drawn at the centre of the whole
/// picture, and the text form parses back to the same camera.
#[test]
fn a_user_camera_looks_at_its_target() {
    let mesh = sphere(1.0, 24, 48);
    let mut scene = Scene::new(&mesh);
    scene.markers = vec![marker([0.0, 0.0, 1.0], MarkerKind::Maximum)];
    let spec: View = "camera:0,0,5,0,0,1,0,1,0,30".parse().unwrap();
    let o = RenderOptions {
        view: spec,
        scale: 2.0,
        ..opts(200, 120)
    };
    let cam = scene.camera(&o);
    let [x, y, _] = cam.project([0.0, 0.0, 1.0]);
    assert!(
        (x - 100.0).abs() < 1e-9 && (y - 60.0).abs() < 1e-9,
        "{x} {y}"
    );
    // Vertical field of view: a point at the top edge of the frustum through the target.
    let t = (15f64).to_radians().tan() * 4.0;
    let [_, yt, _] = cam.project([0.0, t, 1.0]);
    assert!(yt.abs() < 1e-6, "{yt}");
    let img = render_scene(&scene, &o).unwrap();
    let c = px(&img, 100.0, 60.0);
    let red = MarkerKind::Maximum.color();
    assert!(
        (0..3).all(|i| (c[i] as i32 - red[i] as i32).abs() <= 12),
        "{c:?}"
    );
    let View::Camera(c) = spec else {
        panic!("not a camera")
    };
    assert_eq!(c.to_string().parse::<View>().unwrap(), spec);
    for bad in [
        "camera:0,0,5,0,0,5,0,1,0,30",
        "camera:0,0,5,0,0,0,0,0,1,30",
        "camera:0,0,5,0,0,0,0,1,0,0",
        "camera:0,0,5",
    ] {
        assert!(bad.parse::<View>().is_err(), "{bad}");
    }
}

#[test]
fn colorbar_spans_the_map_and_has_labels() {
    let mesh = sphere(1.0, 16, 32);
    let field: Vec<f64> = mesh.positions().iter().map(|p| 3.0 * p[1]).collect();
    let scene = Scene::with_field(&mesh, &field, Colormap::Hue, None);
    let bar = scene.colorbar.unwrap();
    assert!((bar.min + 3.0).abs() < 1e-9 && (bar.max - 3.0).abs() < 1e-9);
    let o = opts(480, 360);
    let img = render_scene(&scene, &o).unwrap();
    // The shape sits in the left part: the camera centre is left of the image centre.
    let cam = scene.camera(&o);
    assert!(cam.cx < 240.0);
    // Find the bar: a column in the right strip where colours vary from magenta (top) to red.
    let strip_x0 = 480 - 80;
    let mut found = false;
    for x in strip_x0..480 {
        let col: Vec<[u8; 4]> = (0..360).map(|y| img.pixel(x, y).unwrap()).collect();
        let magenta = col
            .iter()
            .position(|c| c[0] > 240 && c[1] < 15 && c[2] > 240);
        let red = col
            .iter()
            .rposition(|c| c[0] > 240 && c[1] < 15 && c[2] < 15);
        let green = col
            .iter()
            .position(|c| c[0] < 15 && c[1] > 240 && c[2] < 15);
        if let (Some(m), Some(r), Some(g)) = (magenta, red, green) {
            assert!(m < g && g < r);
            found = true;
            // Labels: dark pixels above the top and below the bottom of the bar.
            let dark_above =
                (0..m).any(|y| (strip_x0..480).any(|xx| is_dark(img.pixel(xx, y as u32).unwrap())));
            let dark_below = (r + 3..360)
                .any(|y| (strip_x0..480).any(|xx| is_dark(img.pixel(xx, y as u32).unwrap())));
            assert!(dark_above && dark_below);
            break;
        }
    }
    assert!(found, "no colour bar found");
}

#[test]
fn perspective_and_named_views_fit_the_shape() {
    let mesh = sphere(2.0, 24, 48)
        .map_positions(|p| [p[0] + 5.0, 0.5 * p[1], p[2] - 3.0])
        .unwrap();
    for view in [
        View::Front,
        View::Side,
        View::Top,
        View::Iso,
        "30,-20".parse().unwrap(),
    ] {
        for projection in [
            Projection::Orthographic,
            Projection::Perspective { fov_deg: 40.0 },
        ] {
            let o = RenderOptions {
                view,
                projection,
                ..opts(100, 80)
            };
            let img = render_scene(&Scene::new(&mesh), &o).unwrap();
            for x in 0..100 {
                assert!(is_white(img.pixel(x, 0).unwrap()) && is_white(img.pixel(x, 79).unwrap()));
            }
            for y in 0..80 {
                assert!(is_white(img.pixel(0, y).unwrap()) && is_white(img.pixel(99, y).unwrap()));
            }
            assert!(
                !is_white(img.pixel(50, 40).unwrap()),
                "{view:?} {projection:?}"
            );
        }
    }
    assert!("sideways".parse::<View>().is_err());
    assert_eq!(
        "#ff8000".parse::<Background>().unwrap(),
        Background::Color([255, 128, 0])
    );
    assert_eq!(
        "transparent".parse::<Background>().unwrap(),
        Background::Transparent
    );
    assert!("#ff80".parse::<Background>().is_err());
    assert_eq!(
        "perspective:30".parse::<Projection>().unwrap(),
        Projection::Perspective { fov_deg: 30.0 }
    );
    assert!("fisheye".parse::<Projection>().is_err());
}

/// The names of views, backgrounds, projections and colour maps, aliases included, in
/// any case and with spaces around, parse to what they name.
#[test]
fn option_names_parse_in_any_case() {
    fn parses_to<T>(text: &str, value: T)
    where
        T: std::str::FromStr + PartialEq + std::fmt::Debug,
        T::Err: std::fmt::Debug,
    {
        assert_eq!(text.parse::<T>().unwrap(), value, "{text:?}");
    }
    parses_to("FRONT", View::Front);
    parses_to(" Iso ", View::Iso);
    parses_to("None", Background::Transparent);
    parses_to("\tWHITE", Background::White);
    parses_to("Ortho", Projection::Orthographic);
    parses_to("PERSPECTIVE", Projection::Perspective { fov_deg: 40.0 });
    parses_to("Gray", Colormap::Grey);
    parses_to(" hsv ", Colormap::Hue);
    parses_to(
        "Camera:0,0,5,0,0,0,0,1,0,30",
        "camera:0,0,5,0,0,0,0,1,0,30".parse::<View>().unwrap(),
    );
    assert!("front,".parse::<View>().is_err());
    assert!("jet".parse::<Colormap>().is_err());
}

#[test]
fn bad_inputs_are_errors() {
    let mesh = quad(2);
    let o = opts(0, 10);
    assert!(matches!(
        render_scene(&Scene::new(&mesh), &o),
        Err(RenderError::InvalidSize { .. })
    ));
    let mut s = Scene::new(&mesh);
    s.vertex_colors.pop();
    assert!(matches!(
        render_scene(&s, &opts(10, 10)),
        Err(RenderError::ColorCount { .. })
    ));
    // NaN colours and fields do not panic.
    let field = vec![f64::NAN; mesh.n_vertices()];
    let s = Scene::with_field(&mesh, &field, Colormap::Turbo, None);
    assert!(render_scene(&s, &opts(20, 20)).is_ok());
}

#[test]
fn tiny_and_odd_sizes_do_not_panic() {
    let mesh = sphere(1.0, 8, 16);
    let field: Vec<f64> = mesh.positions().iter().map(|p| p[0]).collect();
    let mut scene = Scene::with_field(&mesh, &field, Colormap::Viridis, None);
    scene.level_sets = extract_level_sets(&mesh, &field, &[0.0, 0.5]);
    scene.markers = vec![marker([1.0, 0.0, 0.0], MarkerKind::Maximum)];
    for (w, h) in [(1, 1), (2, 3), (7, 1), (41, 5), (300, 17)] {
        for ss in [1, 4] {
            let o = RenderOptions {
                supersample: ss,
                scale: 20.0,
                line_width: 9.0,
                ..opts(w, h)
            };
            let img = render_scene(&scene, &o).unwrap();
            assert_eq!((img.width, img.height), (w, h));
            assert_eq!(img.rgba.len(), (w * h * 4) as usize);
            assert!(img.png_bytes().unwrap().starts_with(b"\x89PNG"));
        }
    }
}

#[test]
fn png_round_trip() {
    let mesh = sphere(1.0, 12, 24);
    let img = render_scene(&Scene::new(&mesh), &opts(64, 48)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.png");
    img.save_png(&path).unwrap();
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (64, 48));
    assert_eq!(&buf[..info.buffer_size()], &img.rgba[..]);
}

#[test]
fn vrml_round_trip_counts() {
    let mesh = sphere(1.0, 16, 32);
    let field: Vec<f64> = mesh.positions().iter().map(|p| p[2]).collect();
    let mut scene = Scene::with_field(&mesh, &field, Colormap::Hue, None);
    scene.level_sets = extract_level_sets(&mesh, &field, &level_values(-1.0, 1.0, 7));
    scene.level_sets.push(LevelSet {
        value: 99.0,
        segments: vec![],
        polylines: vec![],
    });
    scene.markers = vec![
        marker([0.0, 0.0, 1.0], MarkerKind::Maximum),
        marker([0.0, 0.0, -1.0], MarkerKind::Minimum),
        marker([1.0, 0.0, 0.0], MarkerKind::Source),
    ];
    let mut out = Vec::new();
    write_vrml(&mut out, &scene).unwrap();
    let text = String::from_utf8(out).unwrap();
    assert!(text.starts_with("#VRML V2.0 utf8"));
    let s = parse_vrml_summary(&text).unwrap();
    assert_eq!(s.n_points, mesh.n_vertices());
    assert_eq!(s.n_colors, mesh.n_vertices());
    assert_eq!(s.n_faces, mesh.n_triangles());
    assert_eq!(s.n_line_sets, 7);
    let pts: usize = scene
        .level_sets
        .iter()
        .flat_map(|l| &l.polylines)
        .map(|p| p.points.len())
        .sum();
    assert_eq!(s.n_line_points, pts);
    assert_eq!(s.n_spheres, 3);
    // The face set's first coordinate reads back exactly, and the flags are there.
    let nodes = parse_vrml(&text).unwrap();
    let ifs = nodes[0].child("geometry").unwrap();
    assert_eq!(ifs.kind, "IndexedFaceSet");
    let coords = ifs.child("coord").unwrap().numbers("point");
    assert_eq!(&coords[..3], &mesh.positions()[0][..]);
    assert_eq!(
        ifs.field("solid"),
        Some(&spectral_mesh_render::vrml::VrmlValue::Words(vec![
            "FALSE".into()
        ]))
    );
}

fn decode_png(path: &std::path::Path) -> (u32, u32, Vec<u8>) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

#[test]
fn plots_write_valid_png_and_svg() {
    let dir = tempfile::tempdir().unwrap();
    let values: Vec<f64> = (0..30).map(|i| (i as f64).powf(1.1) * 0.5).collect();
    let png_path = dir.path().join("spectrum.png");
    plots::plot_spectrum(&png_path, &values, "spectrum").unwrap();
    let (w, h, buf) = decode_png(&png_path);
    assert_eq!((w, h), plots::PLOT_SIZE);
    let non_white = buf
        .chunks_exact(4)
        .filter(|c| c[..3] != [255, 255, 255])
        .count();
    assert!(non_white > 2000, "plot has ink: {non_white}");

    let svg_path = dir.path().join("spectrum.svg");
    plots::plot_spectrum(&svg_path, &values, "spectrum").unwrap();
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    assert!(svg.contains("<svg") && svg.contains("spectrum"));

    // Filter curves on a log axis (the paper's Fig. 7 shape).
    let s: Vec<f64> = (0..200).map(|i| i as f64 * 0.05).collect();
    let curves = vec![
        (
            "heat t=1".to_string(),
            s.iter().map(|&x| (x, (-x).exp())).collect(),
        ),
        (
            "biharmonic".to_string(),
            s.iter().map(|&x| (x, 1.0 / (x * x))).collect::<Vec<_>>(),
        ),
        (
            "commute".to_string(),
            s.iter().map(|&x| (x, 1.0 / x)).collect::<Vec<_>>(),
        ),
    ];
    for ext in ["png", "svg"] {
        let p = dir.path().join(format!("filters.{ext}"));
        plots::plot_curves(&p, &curves, "s", "w(s)", true, "filters").unwrap();
        if ext == "png" {
            let (_, _, buf) = decode_png(&p);
            // Three different curve colours are present.
            let has = |c: [u8; 3]| buf.chunks_exact(4).any(|p| p[..3] == c);
            assert!(has([31, 119, 180]) && has([214, 39, 40]) && has([44, 160, 44]));
        } else {
            let t = std::fs::read_to_string(&p).unwrap();
            assert!(t.contains("<svg") && t.contains("biharmonic"));
        }
    }
    // Nothing plottable is an error, not a panic.
    let bad = vec![("x".to_string(), vec![(0.0, -1.0), (1.0, f64::NAN)])];
    assert!(plots::plot_curves(dir.path().join("bad.png"), &bad, "k", "e", true, "t").is_err());
}
