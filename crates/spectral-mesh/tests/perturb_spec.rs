//! The perturbation spec parser (forms, round trips, error tokens) and the random
//! generator (moments, determinism). Kept as an integration test so its binary name is
//! unique in a shared target folder.

use spectral_mesh::perturb::rng::Rng;
use spectral_mesh::perturb::{
    Center, PerturbError, PerturbationSpec, ResampleMode, parse_perturbation,
};

#[test]
fn parses_the_documented_forms() {
    use PerturbationSpec as P;
    #[rustfmt::skip]
    let cases = [
        ("noise:0.1", P::Noise { magnitude: 0.1, seed: 0 }),
        (" noise:0.1, seed=3 ", P::Noise { magnitude: 0.1, seed: 3 }),
        ("scale:2", P::Scale { alpha: 2.0 }),
        ("rotate:axis=z,angle=30",
         P::RigidMotion { axis: [0.0, 0.0, 1.0], angle_deg: 30.0, translation: [0.0; 3] }),
        ("rotate:axis=1/1/0,angle=45,t=1/2/3",
         P::RigidMotion { axis: [1.0, 1.0, 0.0], angle_deg: 45.0, translation: [1.0, 2.0, 3.0] }),
        ("resample:2", P::Resample { factor: 2.0, seed: 0, mode: ResampleMode::AreaWeighted }),
        ("refine:0.5,0,-1,0.25,2",
         P::Refine { center: Center::Point([0.5, 0.0, -1.0]), radius: 0.25, levels: 2 }),
        ("hole:v=12,0.3", P::Hole { center: Center::Vertex(12), radius: 0.3 }),
        ("tiny:100", P::Tiny { count: 100, seed: 0 }),
        ("missing:20,seed=9", P::Missing { count: 20, seed: 9 }),
        ("bend:90", P::Bend { angle_deg: 90.0, axis: None }),
        ("bend:90,axis=y", P::Bend { angle_deg: 90.0, axis: Some(1) }),
    ];
    for (text, want) in cases {
        assert_eq!(parse_perturbation(text).unwrap(), want, "{text}");
    }
}

#[test]
fn display_round_trips() {
    for s in [
        "noise:0.1,seed=3",
        "scale:0.5",
        "localscale:1,2,3,0.5,1.5",
        "localscale:v=4,0.5,1.5",
        "rotate:axis=0/1/0,angle=-30,t=0.1/0/2",
        "translate:1,2,3",
        "resample:1.5,seed=2",
        "resample:3,mode=irregular",
        "refine:v=0,0.2,3",
        "hole:0,0,1,0.3",
        "tiny:5,seed=1",
        "missing:7",
        "bend:45,axis=x",
        "bend:-45",
    ] {
        let a = parse_perturbation(s).unwrap();
        let b = parse_perturbation(&a.to_string()).unwrap();
        assert_eq!(a, b, "{s} -> {a}");
    }
}

#[test]
fn errors_name_the_bad_token() {
    let cases = [
        ("nosie:0.1", "nosie"),
        ("noise:abc", "abc"),
        ("noise:0.1,seed=-1", "seed=-1"),
        ("noise:0.1,sed=3", "sed=3"),
        ("noise:0.1,7", "7"),
        ("rotate:axis=w,angle=3", "axis=w"),
        ("rotate:axis=1/0,angle=3", "axis=1/0"),
        ("tiny:1.5", "1.5"),
        ("resample:2,mode=fancy", "mode=fancy"),
        ("refine:1,2,3,0.5,x", "x"),
        ("scale:inf", "inf"),
    ];
    for (s, tok) in cases {
        match parse_perturbation(s) {
            Err(PerturbError::Parse { token, .. }) => assert_eq!(token, tok, "{s}"),
            other => panic!("{s}: expected a parse error, got {other:?}"),
        }
    }
    // Missing arguments name the perturbation.
    match parse_perturbation("hole:1,2") {
        Err(PerturbError::Parse { token, .. }) => assert_eq!(token, "hole"),
        other => panic!("{other:?}"),
    }
    assert!(parse_perturbation("noise").is_err());
    assert!(parse_perturbation("noise:0.1,,seed=2").is_err());
}

#[test]
fn normal_moments_and_determinism() {
    let mut r = Rng::new(7);
    let n = 200_000;
    let xs: Vec<f64> = (0..n).map(|_| r.normal()).collect();
    let mean = xs.iter().sum::<f64>() / n as f64;
    let var = xs.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n as f64;
    assert!(mean.abs() < 0.01, "mean {mean}");
    assert!((var - 1.0).abs() < 0.02, "var {var}");
    let mut r2 = Rng::new(7);
    let ys: Vec<f64> = (0..n).map(|_| r2.normal()).collect();
    assert_eq!(xs, ys);
    let mut r3 = Rng::new(8);
    assert_ne!(r3.normal(), xs[0]);
}

#[test]
fn below_is_in_range_and_covers() {
    let mut r = Rng::new(1);
    let mut hit = [0usize; 5];
    for _ in 0..10_000 {
        let k = r.below(5);
        assert!(k < 5);
        hit[k] += 1;
    }
    assert!(hit.iter().all(|&h| h > 1800 && h < 2200), "{hit:?}");
    assert_eq!(r.below(0), 0);
}
