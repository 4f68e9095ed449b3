//! Every default and limit of the project, in one place: the faces (command line, web
//! server and page, Python package, batch) read them from here and state none of their own.
//!
//! Defaults that belong to one type stay beside it and are re-exported here, so this
//! module is the one index: the request defaults ([`DEFAULT_K`], [`DEFAULT_HEAT_T`], ...,
//! `analysis/request/mod.rs`), the eigensolver's (`EigenParams::default()`, the dense-path
//! sizes [`DENSE_MAX_N`] and [`DENSE_MAX_N_LARGE_K`]), the zero-eigenvalue threshold
//! [`ZERO_EIGENVALUE_EPS`] and the default shape [`DEFAULT_SHAPE`]. The rest is defined
//! here: the unit-area normalisation ([`NORMALIZE`]), the picture defaults and bounds
//! ([`LEVELS`], [`PICTURE_SIZE`], [`MIN_PICTURE`], [`MAX_PICTURE`], [`MAX_LEVELS`]; the
//! render crate's `FigureOptions` reads them) and the web server's limits ([`server`]).
//!
//! [`to_json`] writes all of them as one JSON object: the Python package's
//! `_native.defaults()` and the web server's `GET /api/defaults` serve it (each adds the
//! picture options of the render crate: colour map and view).

use serde_json::{Value, json};

use crate::analysis::{AnalysisOptions, FieldRequest};
use crate::batch::BatchParams;
use crate::operators::Laplacian;
use crate::operators::point_cloud::PointCloudParams;

pub use crate::analysis::request::{
    DEFAULT_COMPONENT, DEFAULT_GEODESIC_TIME_FACTOR, DEFAULT_HARMONIC_ORDER, DEFAULT_HEAT_T,
    DEFAULT_K, DEFAULT_PERSISTENCE, DEFAULT_SIGNATURE_T, DEFAULT_WKS_SIGMA, KINDS, MAX_SPEC_LEN,
};
pub use crate::shapes::DEFAULT_SHAPE;
pub use crate::spectral::eigenbasis::{DENSE_MAX_N, DENSE_MAX_N_LARGE_K};
pub use crate::spectral::filters::ZERO_EIGENVALUE_EPS;
pub use values::{
    CLUSTER_TOLERANCE, EMBED_DIMS, LEVELS, MAX_LEVELS, MAX_PICTURE, MIN_PICTURE, NORMALIZE,
    PICTURE_SIZE, check_picture_size, server,
};

pub(crate) mod declare;
pub mod values;

/// The discretization of an input: the one `given`, or the input's default (fem for a
/// mesh, [`Laplacian::Robust`], the point-cloud Laplacian, for a point cloud). A point
/// cloud refuses any other (it needs triangles): the error says why.
pub fn laplacian_for(
    given: Option<Laplacian>,
    point_cloud: bool,
) -> Result<Laplacian, crate::analysis::AnalysisError> {
    match (point_cloud, given) {
        (false, g) => Ok(g.unwrap_or(AnalysisOptions::default().laplacian)),
        (true, None | Some(Laplacian::Robust)) => Ok(Laplacian::Robust),
        (true, Some(laplacian)) => Err(crate::analysis::AnalysisError::NotForPoints { laplacian }),
    }
}

/// Every request kind's keys with their defaults, as the request's serde form writes them
/// (the required per-vertex keys, a diffusion's `signal` and a WKS `energy`, left out).
fn request_defaults() -> serde_json::Map<String, Value> {
    let mut kinds = serde_json::Map::new();
    for kind in KINDS {
        let mut j = json!({ "kind": kind });
        match kind {
            "diffusion" => j["signal"] = json!({ "impulse": 0 }),
            "wks" => j["energy"] = json!(0.0),
            _ => {}
        }
        let v = serde_json::from_value::<FieldRequest>(j)
            .and_then(|r| serde_json::to_value(&r))
            .map_or(Value::Null, |mut v| {
                if let Some(o) = v.as_object_mut() {
                    o.remove("kind");
                    o.remove("signal");
                    o.remove("energy");
                }
                v
            });
        kinds.insert(kind.to_string(), v);
    }
    kinds
}

/// The library's defaults and limits as one JSON object (keys: `requests` (every
/// request kind's defaults), `analysis`, `point_cloud`, `batch`, `pictures`, `server`,
/// `zero_eigenvalue_eps`, `shape`, `laplacians`, `default_laplacian` (`mesh`, `point
/// cloud`)). Python names where the Python package reads it (`tol`, `n_neighbors`).
pub fn to_json() -> Value {
    let a = AnalysisOptions::default();
    let pc = PointCloudParams::default();
    let bp = BatchParams::default();
    let mesh_laplacian = laplacian_for(None, false).map_or("", |l| l.name());
    let cloud_laplacian = laplacian_for(None, true).map_or("", |l| l.name());
    json!({
        "requests": request_defaults(),
        "analysis": {
            "kind": a.laplacian.name(),
            "normalize": a.normalize,
            "k": DEFAULT_K,
            "tol": a.eigen.tolerance,
            "seed": a.eigen.seed,
            "method": "auto",
        },
        "default_laplacian": { "mesh": mesh_laplacian, "point cloud": cloud_laplacian },
        "point_cloud": {
            "n_neighbors": pc.neighbors,
            "mollify_factor": pc.mollify_factor,
            "delaunay_tolerance": pc.delaunay_tolerance,
            "normals": pc.normals,
            "union": pc.union,
        },
        "batch": {
            "k": bp.k,
            "laplacian": bp.solve.laplacian.name(),
            "tol": bp.solve.tolerance,
            "normalize": bp.solve.normalize,
            "eigenvectors": bp.basis,
            "hks": bp.descriptors.hks.as_ref().map(ToString::to_string),
            "wks": bp.descriptors.wks.as_ref().map(ToString::to_string),
            "wks_sigma": bp.descriptors.wks_sigma,
            "adf": bp.descriptors.adf.as_ref().map(ToString::to_string),
            "scaled": bp.descriptors.scaled,
            "thumbnail": bp.thumbnail,
            "geodesic": bp.geodesic,
        },
        "correspondence": serde_json::to_value(crate::correspondence::MatchParams::default()).unwrap_or(Value::Null),
        "pairs": crate::batch::pairs::defaults_json(),
        "pictures": {
            "levels": LEVELS,
            "max_levels": MAX_LEVELS,
            "size": PICTURE_SIZE,
            "min_size": MIN_PICTURE,
            "max_size": MAX_PICTURE,
        },
        "server": server::to_json(),
        "zero_eigenvalue_eps": ZERO_EIGENVALUE_EPS,
        "shape": DEFAULT_SHAPE,
        "laplacians": Laplacian::ALL.iter().map(|l| l.name()).collect::<Vec<_>>(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_request_kind_has_its_defaults() {
        let j = to_json();
        for kind in KINDS {
            assert!(
                j["requests"][kind].is_object(),
                "{kind}: {}",
                j["requests"][kind]
            );
        }
        assert_eq!(j["requests"]["heat"]["t"], json!(DEFAULT_HEAT_T));
        assert_eq!(j["requests"]["heat"]["k"], json!(DEFAULT_K));
        assert_eq!(j["analysis"]["normalize"], json!(NORMALIZE));
        assert_eq!(j["pictures"]["levels"], json!(LEVELS));
        assert_eq!(j["default_laplacian"]["point cloud"], json!("robust"));
        assert_eq!(j["default_laplacian"]["mesh"], json!("fem"));
    }

    #[test]
    fn structs_with_defaults_default_to_what_their_fields_say() {
        use crate::experiments::harmonic::HarmonicExperimentParams;
        use crate::experiments::study::StudyParams;
        use crate::experiments::truncation::{TruncationParams, TruncationReference};
        let t = TruncationParams::default();
        assert_eq!(
            t.laplacians,
            [Laplacian::Cot, Laplacian::VoronoiCot, Laplacian::Fem]
        );
        assert_eq!(t.times, [0.01, 0.05, 0.1]);
        assert_eq!(t.ks, [10, 20, 50, 100, 200, usize::MAX]);
        assert_eq!(
            (t.anchor, t.reference, t.dense_max_n),
            (None, TruncationReference::Auto, 2500)
        );
        let s = StudyParams::default();
        assert_eq!(
            (s.k, s.heat_t, s.diffusion_t, s.hks_t, s.source),
            (60, 0.05, 0.05, 0.01, None)
        );
        let h = HarmonicExperimentParams::default();
        assert_eq!(h.constraint_counts, [2, 4, 6]);
        assert_eq!(
            (h.order, h.laplacian, h.locality_rings),
            (1, Laplacian::Fem, 2)
        );
        let a = AnalysisOptions::default();
        assert_eq!((a.laplacian, a.normalize), (Laplacian::Fem, NORMALIZE));
        let b = BatchParams::default();
        assert_eq!(
            (b.k, b.basis, b.thumbnail, b.geodesic),
            (DEFAULT_K, true, None, None)
        );
        assert_eq!(
            (b.solve.laplacian, b.solve.tolerance, b.solve.normalize),
            (a.laplacian, a.eigen.tolerance, a.normalize)
        );
        let p = crate::batch::pairs::PairParams::default();
        assert_eq!(
            p.max_geodesic_sources,
            Some(crate::batch::pairs::DEFAULT_PAIR_GEODESIC_SOURCES)
        );
        assert_eq!(p.solve, b.solve);
    }

    #[test]
    fn the_server_limits_keep_their_keys() {
        let j = to_json();
        let keys: Vec<&str> = j["server"]
            .as_object()
            .unwrap()
            .keys()
            .map(String::as_str)
            .collect();
        let mut expected = vec![
            "port",
            "memory_mib",
            "cache_mib",
            "max_upload_mib",
            "max_json_bytes",
            "max_vertices",
            "max_faces",
            "max_shape_vertices",
            "max_k",
            "max_jobs",
            "max_queued",
            "job_seconds",
            "job_idle_seconds",
            "request_seconds",
            "max_requests",
            "idle_seconds",
        ];
        expected.sort_unstable();
        let mut keys = keys;
        keys.sort_unstable();
        assert_eq!(keys, expected);
        assert_eq!(j["server"]["port"], json!(server::PORT));
        assert_eq!(j["server"]["max_json_bytes"], json!(1 << 20));
        assert_eq!(j["server"]["max_shape_vertices"], json!(2_000_000));
        assert_eq!(j["server"]["idle_seconds"], json!(server::IDLE_SECONDS));
    }

    #[test]
    fn the_laplacian_of_an_input() {
        assert_eq!(laplacian_for(None, false), Ok(Laplacian::Fem));
        assert_eq!(
            laplacian_for(Some(Laplacian::Cot), false),
            Ok(Laplacian::Cot)
        );
        assert_eq!(laplacian_for(None, true), Ok(Laplacian::Robust));
        let e = laplacian_for(Some(Laplacian::Cot), true).unwrap_err();
        assert!(e.to_string().contains("needs triangles"), "{e}");
    }

    #[test]
    fn picture_bounds() {
        assert!(check_picture_size(PICTURE_SIZE).is_ok());
        assert!(check_picture_size(MAX_PICTURE).is_ok());
        let e = check_picture_size(MAX_PICTURE + 1).unwrap_err();
        assert!(e.contains(&MAX_PICTURE.to_string()), "{e}");
        assert!(check_picture_size(MIN_PICTURE - 1).is_err());
    }
}
