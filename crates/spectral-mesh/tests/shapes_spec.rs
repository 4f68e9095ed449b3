//! Spec strings: parsing, errors, printing, the name list and the file/shape distinction.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use spectral_mesh::shapes::{
    DEFAULT_SHAPE, ShapeError, ShapeKind, ShapeSpec, build, build_str, is_shape_spec, parse_shape,
    shape_names,
};

#[test]
fn parses_the_documented_examples() {
    let s = parse_shape("3torus").unwrap();
    assert_eq!(s, ShapeSpec::new(ShapeKind::ThreeTorus));
    assert_eq!(s.res, 3);
    assert!(!s.irregular);

    let s = parse_shape("sphere:res=4").unwrap();
    assert_eq!((s.kind, s.res), (ShapeKind::Sphere, 4));

    let s = parse_shape("torus:res=3,R=1,r=0.4").unwrap();
    assert_eq!(s.kind, ShapeKind::Torus);
    assert_eq!(s.param("R"), Some(1.0));
    assert_eq!(s.param("r"), Some(0.4));
    assert_eq!(s.param("res"), Some(3.0));

    let s = parse_shape("torus: R = 2 , r=0.25 ").unwrap();
    assert_eq!(s.values, vec![2.0, 0.25]);
    assert_eq!(s.res, ShapeKind::Torus.default_res());

    let s = parse_shape("irregular-sphere:res=3").unwrap();
    assert!(s.irregular);
    assert_eq!(s, parse_shape("sphere:res=3,irregular=1").unwrap());
    assert_eq!(s.name(), "irregular-sphere");

    assert_eq!(parse_shape("3-torus").unwrap().kind, ShapeKind::ThreeTorus);
    assert_eq!(
        parse_shape("Double-Torus").unwrap().kind,
        ShapeKind::DoubleTorus
    );
    assert_eq!(parse_shape("cylinder:h=3").unwrap().param("h"), Some(3.0));
    assert_eq!(parse_shape(DEFAULT_SHAPE).unwrap(), ShapeSpec::default());
}

#[test]
fn display_round_trips() {
    for s in [
        "3torus",
        "torus:res=2,R=1.5,r=0.1",
        "irregular-cylinder:res=4,r=0.3,h=7",
        "uv-sphere:res=0",
        "irregular-disk",
    ] {
        let spec = parse_shape(s).unwrap();
        let printed = spec.to_string();
        assert_eq!(parse_shape(&printed).unwrap(), spec, "{s} -> {printed}");
    }
    assert_eq!(
        parse_shape("torus").unwrap().to_string(),
        "torus:res=3,R=1,r=0.4"
    );
    assert_eq!(
        parse_shape("irregular-sphere:res=2").unwrap().to_string(),
        "irregular-sphere:res=2"
    );
}

#[test]
fn errors_name_the_offending_token_and_list_valid_choices() {
    let e = parse_shape("donut:res=2").unwrap_err();
    assert!(matches!(&e, ShapeError::UnknownShape { name, .. } if name == "donut"));
    let msg = e.to_string();
    assert!(msg.contains("donut") && msg.contains("3torus") && msg.contains("irregular-disk"));

    let e = parse_shape("torus:res=2,radius=3").unwrap_err();
    assert!(matches!(&e, ShapeError::UnknownParam { param, .. } if param == "radius"));
    let msg = e.to_string();
    assert!(
        msg.contains("radius") && msg.contains("R") && msg.contains("res"),
        "{msg}"
    );

    let e = parse_shape("sphere:R=2").unwrap_err();
    assert!(matches!(e, ShapeError::UnknownParam { .. }));

    let e = parse_shape("sphere:res").unwrap_err();
    assert!(matches!(&e, ShapeError::Malformed { token } if token == "res"));

    let e = parse_shape("sphere:res=2,res=3").unwrap_err();
    assert!(matches!(e, ShapeError::Duplicate { .. }));

    for bad in [
        "sphere:res=-1",
        "sphere:res=1.5",
        "sphere:res=99",
        "3torus:res=8",
        "torus:r=1.2",
        "torus:R=0.3",
        "torus:r=nan",
        "torus:r=inf",
        "cylinder:h=0",
        "cylinder:r=-1",
        "disk:irregular=2",
    ] {
        let e = parse_shape(bad).unwrap_err();
        assert!(matches!(e, ShapeError::BadValue { .. }), "{bad}: {e}");
    }
    assert!(matches!(parse_shape("  "), Err(ShapeError::Empty { .. })));
    assert!(matches!(
        parse_shape(":res=2"),
        Err(ShapeError::UnknownShape { .. })
    ));
}

#[test]
fn build_validates_hand_made_specs() {
    let mut s = ShapeSpec::new(ShapeKind::Torus);
    s.values = vec![1.0];
    assert!(build(&s).is_err());
    s.values = vec![1.0, 2.0];
    assert!(build(&s).is_err());
    let s = ShapeSpec::new(ShapeKind::Sphere).with_res(40);
    assert!(matches!(build(&s), Err(ShapeError::BadValue { .. })));
    assert!(build_str("sphere:res=1").is_ok());
}

#[test]
fn tells_shape_names_from_file_paths() {
    for yes in [
        "3torus",
        "sphere:res=4",
        "irregular-torus:res=2",
        "Torus",
        "sphere:bogus=1",
    ] {
        assert!(is_shape_spec(yes), "{yes}");
    }
    for no in [
        "3torus.off",
        "./3torus",
        "meshes/sphere",
        "C:\\meshes\\torus",
        "bunny.PLY",
        "cow.obj",
        "part.stl",
        "bunny",
        "",
    ] {
        assert!(!is_shape_spec(no), "{no}");
    }
}

#[test]
fn name_list_covers_every_shape_and_its_irregular_variant() {
    let names = shape_names();
    assert_eq!(names.len(), 14);
    for info in &names {
        let spec = parse_shape(&info.name).unwrap();
        assert_eq!(spec.name(), info.name);
        assert_eq!(info.topology, spec.kind.expected_topology());
        assert_eq!(info.params[0].name, "res");
        assert_eq!(info.params[0].default, f64::from(spec.res));
        assert_eq!(info.params.last().map(|p| p.name), Some("irregular"));
        assert_eq!(info.default_vertices, spec.vertex_count());
        assert!(!info.description.is_empty());
    }
    let dv = |n: &str| names.iter().find(|i| i.name == n).unwrap().default_vertices;
    // The values in the documentation table.
    assert_eq!(dv("3torus"), Some(6396));
    assert_eq!(dv("torus"), Some(6272));
    assert_eq!(dv("sphere"), Some(2562));
    assert_eq!(dv("uv-sphere"), Some(6162));
    assert_eq!(dv("double-torus"), Some(4734));
    assert_eq!(dv("disk"), Some(7057));
    assert_eq!(dv("cylinder"), Some(6384));
    assert_eq!(dv("irregular-3torus"), None);
}

#[test]
fn build_limited_refuses_specs_over_the_budget_before_building() {
    use spectral_mesh::shapes::{build_limited, parse_shape};
    // Regular: the formula decides, nothing is built (6.4 million vertices, about 4 GB).
    let big = parse_shape("torus:res=8").unwrap();
    match build_limited(&big, 100_000) {
        Err(ShapeError::TooLarge {
            vertices, limit, ..
        }) => {
            assert_eq!(vertices, 6_422_528);
            assert_eq!(limit, 100_000);
        }
        other => panic!("{other:?}"),
    }
    let e = build_limited(&big, 100_000).unwrap_err().to_string();
    assert!(e.contains("torus:res=8") && e.contains("100000"), "{e}");
    // Exactly at the budget is fine.
    let s = parse_shape("sphere:res=2").unwrap();
    assert_eq!(build_limited(&s, 162).unwrap().n_vertices(), 162);
    assert!(matches!(
        build_limited(&s, 161),
        Err(ShapeError::TooLarge { vertices: 162, .. })
    ));
    // Irregular: the bound (vertices + edges before each level) holds the built size.
    let irr = parse_shape("irregular-torus:res=3").unwrap();
    let full = build(&irr).unwrap().n_vertices();
    let m = build_limited(&irr, 4 * full).unwrap();
    assert_eq!(m.n_vertices(), full);
    assert!(matches!(
        build_limited(&irr, full / 2),
        Err(ShapeError::TooLarge { .. })
    ));
    // The coarse base alone can be over the budget.
    let huge = parse_shape("irregular-sphere:res=9").unwrap();
    assert!(matches!(
        build_limited(&huge, 50_000),
        Err(ShapeError::TooLarge {
            vertices: 163_842,
            ..
        })
    ));
}

#[test]
fn parameters_that_would_give_zero_area_triangles_are_refused() {
    for (spec, words) in [
        ("torus:R=1e300,r=1e-300", "between 1e-100 and 1e100"),
        ("torus:R=1,r=1e-7", "at least R / 1e6"),
        ("cylinder:r=1,h=1e-40", "between r / 1e6 and r * 1e6"),
        ("cylinder:r=1e-3,h=1e4", "between r / 1e6 and r * 1e6"),
    ] {
        let e = parse_shape(spec).unwrap_err().to_string();
        assert!(e.contains(words), "{spec}: {e}");
    }
    // The limits themselves build clean meshes.
    for spec in [
        "torus:res=2,R=1,r=1e-6",
        "cylinder:res=2,r=1,h=1e-6",
        "cylinder:res=1,r=1,h=1e6",
    ] {
        let m = build_str(spec).unwrap();
        let r = spectral_mesh::mesh::validate::report(&m);
        assert!(r.degenerate_faces.is_empty(), "{spec}: {:?}", r.problems());
    }
}
