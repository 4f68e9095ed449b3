//! Tests of the request type: serde forms, texts, validation.

use super::*;
use crate::fields::harmonic::Constraint;
use crate::geodesic::Convention;

fn json(v: &str) -> Result<FieldRequest, String> {
    serde_json::from_str(v).map_err(|e| e.to_string())
}

#[test]
fn defaults_fill_every_missing_key() {
    assert_eq!(
        json(r#"{"kind": "distance"}"#).unwrap(),
        FieldRequest::default()
    );
    assert_eq!(
        json(r#"{"kind": "heat"}"#).unwrap(),
        FieldRequest::Heat {
            anchor: None,
            t: 0.5,
            kernel: Kernel::Wfem,
            k: 100
        }
    );
    assert_eq!(
        json(r#"{"kind": "harmonic"}"#).unwrap(),
        FieldRequest::Harmonic {
            constraints: Constraints::Preset(2),
            order: 1
        }
    );
}

#[test]
fn unknown_keys_and_kinds_are_refused_by_name() {
    let e = json(r#"{"kind": "distance", "filter": "biharmonic"}"#).unwrap_err();
    assert!(e.contains("filter"), "{e}");
    let e = json(r#"{"kind": "geodesics"}"#).unwrap_err();
    assert!(e.contains("geodesics"), "{e}");
    let e = json(r#"{"kind": "geodesic", "t": 1}"#).unwrap_err();
    assert!(e.contains("`t`"), "{e}");
    let e = json(r#"{"kind": "distance", "distance": "diffusion:t=-1"}"#).unwrap_err();
    assert!(e.contains("t"), "{e}");
}

#[test]
fn every_kind_round_trips_through_json_and_toml() {
    let reqs = vec![
        FieldRequest::Harmonic {
            constraints: Constraints::List(vec![
                Constraint {
                    vertex: 3,
                    value: 0.25,
                },
                Constraint {
                    vertex: 9,
                    value: -1.0,
                },
            ]),
            order: 2,
        },
        FieldRequest::Heat {
            anchor: Some(4),
            t: 0.01,
            kernel: Kernel::Standard,
            k: 30,
        },
        FieldRequest::Diffusion {
            signal: Signal::Ball {
                vertex: 2,
                radius: 0.3,
            },
            t: 0.1,
            kernel: Kernel::VoronoiCot,
            k: 20,
        },
        FieldRequest::Diffusion {
            signal: Signal::Values(vec![1.0, 0.5, 1e-300]),
            t: 0.1,
            kernel: Kernel::Wfem,
            k: 20,
        },
        FieldRequest::Distance {
            source: Some(1),
            distance: "wfem-diffusion:t=0.125".parse().unwrap(),
            k: 50,
        },
        FieldRequest::Distance {
            source: None,
            distance: "custom-w:exp(-t*s)/s;t=0.1".parse().unwrap(),
            k: 50,
        },
        FieldRequest::SpectralFunction {
            filter: "mix:a=0.3,t=0.7".parse().unwrap(),
            k: 10,
        },
        FieldRequest::Hks {
            t: 0.3,
            scaled: true,
            k: 10,
        },
        FieldRequest::Wks {
            energy: 2.5,
            sigma: 0.25,
            scaled: false,
            k: 10,
        },
        FieldRequest::Adf { t: 0.2, k: 10 },
        FieldRequest::Segmentation {
            signature: "wks:e=2,sigma=0.5".parse().unwrap(),
            persistence: 0.1,
            k: 10,
        },
        FieldRequest::Segmentation {
            signature: SignatureSpec::Values(vec![0.0, 1.0, 2.0]),
            persistence: 0.1,
            k: 10,
        },
        FieldRequest::Embedding {
            filter: Filter::CommuteTime,
            component: 3,
            k: 10,
        },
        FieldRequest::Eigenfunction { index: 2, k: 10 },
        FieldRequest::Green {
            source: Some(7),
            filter: "band:1,2".parse().unwrap(),
            k: 10,
        },
        FieldRequest::Geodesic {
            source: Some(4),
            sources: vec![9, 2],
            time_factor: 2.5,
            convention: Convention::Potpourri3d,
        },
        FieldRequest::Geodesic {
            source: None,
            sources: Vec::new(),
            time_factor: DEFAULT_GEODESIC_TIME_FACTOR,
            convention: Convention::Crane,
        },
    ];
    for k in KINDS {
        assert!(reqs.iter().any(|r| r.kind() == k), "{k} is not tested");
    }
    for r in reqs {
        r.validate().unwrap();
        let j = serde_json::to_string(&r).unwrap();
        assert_eq!(json(&j).unwrap(), r, "{j}");
        let t = toml::to_string(&r).unwrap();
        let back: FieldRequest = toml::from_str(&t).unwrap();
        assert_eq!(back, r, "{t}");
    }
}

#[test]
fn a_geodesic_request_has_a_source_no_basis_and_the_library_defaults() {
    let r = json(r#"{"kind": "geodesic"}"#).unwrap();
    assert_eq!(
        r,
        FieldRequest::Geodesic {
            source: None,
            sources: Vec::new(),
            time_factor: 1.0,
            convention: Convention::Crane,
        }
    );
    assert_eq!(
        crate::geodesic::GeodesicParams::default().time_factor,
        DEFAULT_GEODESIC_TIME_FACTOR
    );
    assert_eq!(r.eigenpairs(), None);
    assert!(r.uses_source() && r.time().is_none());
    let mut r =
        json(r#"{"kind": "geodesic", "sources": [5, 1], "convention": "potpourri3d"}"#).unwrap();
    assert_eq!(r.source(), Some(5));
    r.set_source(Some(8));
    assert_eq!(r.source(), Some(8));
    assert!(matches!(&r, FieldRequest::Geodesic { sources, .. } if sources == &[5, 1]));
    r.set_eigenpairs(3);
    assert_eq!(r.eigenpairs(), None);
    let e = json(r#"{"kind": "geodesic", "convention": "exact"}"#).unwrap_err();
    assert!(e.contains("exact"), "{e}");
}

#[test]
fn validation_names_the_key() {
    let cases = [
        (r#"{"kind": "heat", "t": -1}"#, "t"),
        (r#"{"kind": "heat", "k": 0}"#, "k"),
        (r#"{"kind": "harmonic", "order": 3}"#, "order"),
        (r#"{"kind": "harmonic", "constraints": 5}"#, "constraints"),
        (r#"{"kind": "harmonic", "constraints": []}"#, "constraints"),
        (r#"{"kind": "hks", "t": 0}"#, "t"),
        (r#"{"kind": "wks", "energy": 1, "sigma": 0}"#, "sigma"),
        (
            r#"{"kind": "eigenfunction", "index": 10, "k": 10}"#,
            "index",
        ),
        (
            r#"{"kind": "embedding", "component": 10, "k": 10}"#,
            "component",
        ),
        (
            r#"{"kind": "segmentation", "persistence": -1}"#,
            "persistence",
        ),
        (r#"{"kind": "geodesic", "time_factor": 0}"#, "time_factor"),
        (r#"{"kind": "geodesic", "time_factor": -2}"#, "time_factor"),
    ];
    for (text, key) in cases {
        let e = json(text).unwrap().validate().unwrap_err();
        assert!(e.to_string().starts_with(key), "{text}: {e}");
    }
}

#[test]
fn distance_texts() {
    assert_eq!(
        "wfem-diffusion".parse::<DistanceSpec>().unwrap(),
        DistanceSpec::WfemDiffusion { t: 0.5 }
    );
    assert_eq!(
        "wfem-diffusion:t=0".parse::<DistanceSpec>().unwrap(),
        DistanceSpec::WfemDiffusion { t: 0.0 }
    );
    assert!("wfem-diffusion:t=-2".parse::<DistanceSpec>().is_err());
    assert!("wfem-diffusion:x".parse::<DistanceSpec>().is_err());
    assert!("x".repeat(2000).parse::<DistanceSpec>().is_err());
    for s in ["biharmonic", "diffusion:t=0.25", "wfem-diffusion:t=0.1"] {
        let d: DistanceSpec = s.parse().unwrap();
        assert_eq!(d.to_string(), s);
    }
    assert!("wks:e=1,e=2".parse::<SignatureSpec>().is_err());
    assert!("wks:sigma=1".parse::<SignatureSpec>().is_err());
    assert!("hks:t=-1".parse::<SignatureSpec>().is_err());
}
