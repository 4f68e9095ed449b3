use super::*;
use crate::fields::harmonic::{ConstraintSpec, harmonic_map_with_operators};
use crate::linalg::interior_target;
use crate::shapes::build_str;
use crate::spectral::distances::{distances_from, wfem_diffusion_distances_from};
use crate::spectral::filters::Filter;
use crate::spectral::heat::{HeatSolver, Kernel, ScaleNormalization, normalize_basis};

fn analysis(shape: &str, normalize: bool) -> Analysis {
    Analysis::new(
        build_str(shape).unwrap(),
        AnalysisOptions {
            normalize,
            ..Default::default()
        },
    )
}

fn close(a: &[f64], b: &[f64], rel: f64) {
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
    let err = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(
        err <= rel * scale,
        "max difference {err} against scale {scale}"
    );
}

/// A geodesic-distance request (the default convention) from `source` and `sources`, with
/// the time factor `m` of `t = m h^2`.
fn geodesic(source: Option<usize>, sources: Vec<usize>, time_factor: f64) -> FieldRequest {
    FieldRequest::Geodesic {
        source,
        sources,
        time_factor,
        convention: Default::default(),
    }
}

#[test]
fn unit_area_fields_equal_the_normalised_basis_path() {
    // The analysis normalises the operators; the earlier path normalised the basis.
    let an = analysis("sphere:res=3", true);
    let raw = analysis("sphere:res=3", false);
    let k = 30;
    let rb = raw
        .basis(k, &mut |_| {}, &CancelToken::new())
        .unwrap()
        .as_ref()
        .clone();
    let src = an.default_source();
    let heat = an
        .field(&FieldRequest::Heat {
            anchor: None,
            t: 0.01,
            kernel: Kernel::Wfem,
            k,
        })
        .unwrap();
    let old = HeatSolver::new(&rb, Kernel::Wfem, ScaleNormalization::UnitArea)
        .basis_function(src, 0.01)
        .unwrap();
    close(&heat.values, &old, 1e-9);
    assert_eq!(heat.marks, vec![src]);
    assert_eq!(heat.request.source(), Some(src));

    let d = an.field(&FieldRequest::default_with_k(k)).unwrap();
    let nb = normalize_basis(&rb, ScaleNormalization::UnitArea);
    close(
        &d.values,
        &distances_from(&nb, src, &Filter::Biharmonic).unwrap(),
        1e-9,
    );
    let w = an
        .field(&FieldRequest::Distance {
            source: Some(7),
            distance: DistanceSpec::WfemDiffusion { t: 0.05 },
            k,
        })
        .unwrap();
    close(
        &w.values,
        &wfem_diffusion_distances_from(&nb, 7, 0.05).unwrap(),
        1e-9,
    );
    assert!(d.normalized && !raw.options().normalize);
}

#[test]
fn a_larger_k_gives_the_pairs_of_a_direct_solve() {
    // Large enough for the sparse path (a factorization), small enough to be quick.
    let grown = analysis("sphere:res=4", true);
    let c = CancelToken::new();
    let b100 = grown.basis(40, &mut |_| {}, &c).unwrap();
    assert_eq!(b100.k(), 40);
    let b200 = grown.basis(80, &mut |_| {}, &c).unwrap();
    let direct = analysis("sphere:res=4", true)
        .basis(80, &mut |_| {}, &c)
        .unwrap();
    assert_eq!(b200.values, direct.values);
    assert_eq!(b200.vectors, direct.vectors);
    // Each solve factored for its own interior shift (k = 40 and 80 have different
    // targets; a counter, not a timer)...
    assert_ne!(interior_target(40), interior_target(80));
    assert_eq!(grown.factorizations(), 2);
    // ...and k = 85, with the target of 80, reuses that factor and still gives the pairs
    // of a direct solve.
    assert_eq!(interior_target(85), interior_target(80));
    let b85 = grown.basis(85, &mut |_| {}, &c).unwrap();
    assert_eq!(grown.factorizations(), 2);
    let direct = analysis("sphere:res=4", true)
        .basis(85, &mut |_| {}, &c)
        .unwrap();
    assert_eq!(b85.values, direct.values);
    assert_eq!(b85.vectors, direct.vectors);
    // Fewer pairs reuse the held basis: no new solve.
    let again = grown.basis(10, &mut |_| {}, &c).unwrap();
    assert!(Arc::ptr_eq(&again, &b85));
}

#[test]
fn fewer_pairs_use_the_prefix_of_the_held_basis() {
    let an = analysis("sphere:res=3", true);
    let c = CancelToken::new();
    let b = an.basis(40, &mut |_| {}, &c).unwrap();
    let req = FieldRequest::default_with_k(20);
    let f = an.field_if_ready(&req).unwrap().unwrap();
    assert_eq!((f.k, f.basis_k), (Some(20), Some(40)));
    close(
        &f.values,
        &distances_from(b.view(20), an.default_source(), &Filter::Biharmonic).unwrap(),
        0.0,
    );
    // Not enough pairs held: the fast path says so instead of solving.
    assert!(
        an.field_if_ready(&FieldRequest::default_with_k(41))
            .unwrap()
            .is_none()
    );
}

#[test]
fn harmonic_requests_match_the_library_and_reuse_the_factor() {
    let an = analysis("3torus", true);
    let req = FieldRequest::Harmonic {
        constraints: Constraints::Preset(4),
        order: 1,
    };
    let f = an.field(&req).unwrap();
    let list = ConstraintSpec::Extremes(4).resolve(an.mesh()).unwrap();
    let want = harmonic_map_with_operators(an.mesh(), an.operators(), &list, 1).unwrap();
    assert_eq!(f.values, want);
    assert_eq!(f.constraints, list);
    assert_eq!(f.k, None);
    // New values on the same vertices reuse the cached solver.
    let moved: Vec<Constraint> = list
        .iter()
        .map(|c| Constraint {
            vertex: c.vertex,
            value: 2.0 * c.value,
        })
        .collect();
    let g = an
        .field(&FieldRequest::Harmonic {
            constraints: Constraints::List(moved),
            order: 1,
        })
        .unwrap();
    close(
        &g.values,
        &f.values.iter().map(|v| 2.0 * v).collect::<Vec<_>>(),
        1e-12,
    );
    assert_eq!(lock(&an.harmonic).len(), 1);
}

#[test]
fn every_kind_gives_a_finite_field_of_n_values() {
    // Not a sphere: its signatures are constant by symmetry.
    let an = analysis("3torus", true);
    let n = an.n();
    let reqs: Vec<FieldRequest> = vec![
        serde_json::from_str(r#"{"kind": "heat", "k": 30}"#).unwrap(),
        serde_json::from_str(
            r#"{"kind": "diffusion", "signal": {"ball": {"vertex": 3, "radius": 0.5}}, "k": 30}"#,
        )
        .unwrap(),
        serde_json::from_str(r#"{"kind": "distance", "distance": "commute", "k": 30}"#).unwrap(),
        serde_json::from_str(r#"{"kind": "spectral-function", "k": 30}"#).unwrap(),
        serde_json::from_str(r#"{"kind": "hks", "k": 30}"#).unwrap(),
        serde_json::from_str(r#"{"kind": "wks", "energy": 3.0, "k": 30}"#).unwrap(),
        serde_json::from_str(r#"{"kind": "adf", "k": 30}"#).unwrap(),
        serde_json::from_str(r#"{"kind": "segmentation", "k": 30}"#).unwrap(),
        serde_json::from_str(r#"{"kind": "embedding", "k": 30}"#).unwrap(),
        serde_json::from_str(r#"{"kind": "eigenfunction", "k": 30}"#).unwrap(),
        serde_json::from_str(r#"{"kind": "green", "k": 30}"#).unwrap(),
        serde_json::from_str(r#"{"kind": "harmonic", "order": 2}"#).unwrap(),
    ];
    for r in reqs {
        let f = an.field(&r).unwrap();
        assert_eq!(f.values.len(), n, "{}", r.kind());
        assert!(f.values.iter().all(|v| v.is_finite()), "{}", r.kind());
        assert!(
            f.values.iter().any(|v| *v != f.values[0]),
            "{} is constant",
            r.kind()
        );
    }
    let seg = an
        .field(&FieldRequest::Segmentation {
            signature: SignatureSpec::Values((0..n).map(|i| (i % 7) as f64).collect()),
            persistence: 0.0,
            k: 30,
        })
        .unwrap();
    assert!(seg.labels.is_some() && seg.k.is_none());
}

#[test]
fn errors_name_what_is_wrong() {
    let an = analysis("sphere:res=1", true);
    let n = an.n();
    let e = an
        .field(&FieldRequest::Distance {
            source: Some(n),
            distance: DistanceSpec::default(),
            k: 5,
        })
        .unwrap_err();
    assert!(
        e.to_string()
            .starts_with(&format!("source {n} is out of range")),
        "{e}"
    );
    let e = an.field(&FieldRequest::default_with_k(n + 1)).unwrap_err();
    assert!(matches!(e, AnalysisError::TooManyPairs { .. }), "{e}");
    let e = an
        .field(&FieldRequest::Diffusion {
            signal: Signal::Values(vec![1.0; 3]),
            t: 0.1,
            kernel: Kernel::Wfem,
            k: 5,
        })
        .unwrap_err();
    assert!(e.to_string().contains("signal has 3 values"), "{e}");
}

#[test]
fn a_component_without_constraints_floats_and_is_left_out_of_the_critical_points() {
    // Two disjoint tori; the preset constraints (min x, max x) both fall on the first.
    let (mesh, n0) = two_copies("torus:res=2");
    let an = Analysis::new(mesh, AnalysisOptions::default());
    let field = an.field(&FieldRequest::Harmonic {
        constraints: Constraints::List(vec![
            Constraint {
                vertex: 0,
                value: 0.0,
            },
            Constraint {
                vertex: 7,
                value: 1.0,
            },
        ]),
        order: 1,
    });
    let field = field.unwrap();
    assert_eq!(field.floating.len(), 1);
    assert_eq!(field.floating[0].first_vertex, n0);
    assert!(field.values[n0..].iter().all(|&v| v == 0.5));
    let all = an.critical_points(&field.values).unwrap();
    let rep = an.field_critical_points(&field).unwrap();
    assert_eq!(
        rep.left_out.excluded_components,
        vec![field.floating[0].component]
    );
    assert!(rep.points.minima.iter().all(|&v| v < n0));
    assert!(rep.points.maxima.iter().all(|&v| v < n0));
    assert!(rep.points.saddles.iter().all(|&(v, _)| v < n0));
    // The constrained torus alone: m - s + M = 0.
    assert_eq!(rep.components.len(), 1);
    assert!(rep.check.holds && rep.chi == 0, "{rep:?}");
    // Without the exclusion, the constant torus is a plateau: left out all the same.
    assert_eq!(
        all.left_out.plateau_components,
        vec![field.floating[0].component]
    );
    assert!(rep.left_out.plateau_components.is_empty() && !rep.left_out.flat && !all.left_out.flat);
    assert_eq!((all.counts, all.check.holds), (rep.counts, true));
}

#[test]
fn a_critical_report_keeps_its_json_keys_flat() {
    // The faces read these keys: the groups of the report are flattened into them.
    let an = analysis("torus:res=2", true);
    let x: Vec<f64> = an.mesh().positions().iter().map(|p| p[0]).collect();
    let rep = an.critical_points(&x).unwrap();
    let keys = |v: &serde_json::Value| -> Vec<String> {
        let mut k: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
        k.sort();
        k
    };
    let sorted = |k: &[&str]| -> Vec<String> {
        let mut k: Vec<String> = k.iter().map(|s| s.to_string()).collect();
        k.sort();
        k
    };
    let v = serde_json::to_value(&rep).unwrap();
    assert_eq!(
        keys(&v),
        sorted(&[
            "points",
            "minima",
            "maxima",
            "saddles",
            "chi",
            "doubled",
            "lhs",
            "rhs",
            "holds",
            "formula",
            "components",
            "excluded_components",
            "plateau_components",
            "flat_tolerance",
            "flat",
            "raw",
            "hidden",
            "persistence_threshold",
            "persistence_relative_threshold",
            "persistence_noise_floor",
            "quiet_components",
            "pairs",
        ])
    );
    let raw = ["minima", "maxima", "saddles", "lhs", "rhs", "holds"];
    assert_eq!(keys(&v["raw"]), sorted(&raw));
    assert_eq!(keys(&v["hidden"]), sorted(&raw[..3]));
    let component = ["component", "chi", "lhs", "rhs", "holds"];
    assert_eq!(keys(&v["components"][0]), sorted(&component));
    assert_eq!(v["holds"], true);
    assert_eq!(v["minima"], rep.counts.minima);
}

#[test]
fn a_heat_kernel_at_a_huge_time_is_flat_and_the_hint_follows_t() {
    // t = 1e12: the kernel is the constant 1 (unit area) up to rounding.
    let an = analysis("sphere:res=3", true);
    let heat = |t: f64| {
        an.field(&FieldRequest::Heat {
            anchor: Some(0),
            t,
            kernel: Kernel::Wfem,
            k: 50,
        })
        .unwrap()
    };
    let flat = heat(1e12);
    let rep = an.field_critical_points(&flat).unwrap();
    assert!(rep.left_out.flat, "{rep:?}");
    assert_eq!(
        (rep.counts.minima, rep.counts.maxima, rep.counts.saddles),
        (0, 0, 0)
    );
    assert_eq!(rep.left_out.plateau_components, vec![0]);
    assert_eq!(rep.left_out.flat_tolerance, FLAT_RELATIVE_TOLERANCE);
    // The same kernel at t = 0.05 is not flat: one maximum at the anchor.
    let peaked = heat(0.05);
    let rep = an.field_critical_points(&peaked).unwrap();
    assert!(
        !rep.left_out.flat && rep.check.holds && rep.points.maxima == vec![0],
        "{rep:?}"
    );
    // The hint: the eigenvalues the analysis holds, the warning at a tiny t only.
    let b = an.held_basis().unwrap();
    let h = an.truncation_hint(&peaked).unwrap();
    assert_eq!(h.k, 50);
    assert!(!h.exact && h.lambda_omitted == b.values[49]);
    assert!(h.lambda_first == b.values[1] && !h.warning);
    let tiny = heat(1e-4);
    let h = an.truncation_hint(&tiny).unwrap();
    assert!(
        h.warning && h.t_needed > 1e-4 && h.k_needed.unwrap() > 50,
        "{h:?}"
    );
    // No time, no hint.
    let d = an.field(&FieldRequest::default_with_k(50)).unwrap();
    assert!(an.truncation_hint(&d).is_none());
}

/// Two disjoint copies of `shape`, the second moved by -10 in x.
fn two_copies(shape: &str) -> (Mesh, usize) {
    let t = build_str(shape).unwrap();
    let (p, f) = (t.positions().to_vec(), t.triangles().to_vec());
    let n0 = p.len();
    let mut pos = p.clone();
    pos.extend(p.iter().map(|q| [q[0] - 10.0, q[1], q[2]]));
    let mut tris = f.clone();
    tris.extend(f.iter().map(|t| [t[0] + n0, t[1] + n0, t[2] + n0]));
    (Mesh::new(pos, tris).unwrap(), n0)
}

#[test]
fn a_geodesic_request_is_the_heat_method_in_mesh_units_factored_once() {
    use crate::geodesic::{GeodesicParams, GeodesicSolver};
    // Normalisation does not scale a geodesic distance: it is in the mesh's units.
    let an = analysis("3torus", true);
    let n = an.n();
    let f = an
        .field(&serde_json::from_str(r#"{"kind": "geodesic"}"#).unwrap())
        .unwrap();
    let src = an.default_source();
    let direct = GeodesicSolver::new(an.mesh(), Laplacian::Fem, &GeodesicParams::default())
        .unwrap()
        .distance_from_vertex(src)
        .unwrap();
    assert_eq!(f.values, direct);
    assert_eq!(f.values[src], 0.0);
    assert_eq!(f.marks, vec![src]);
    assert_eq!(f.request.source(), Some(src));
    assert!(f.k.is_none() && f.unreachable.is_empty() && f.unreachable_vertices == 0);
    assert!(f.unreachable_message().is_none());
    assert!(
        an.held_basis().is_none(),
        "a geodesic distance needs no basis"
    );
    let (lo, hi) = f.finite_range().unwrap();
    assert!(lo == 0.0 && hi > 1.0 && hi.is_finite(), "{lo} {hi}");
    // Many sources from one factoring; the set is the distance to the nearest.
    let before = an.memory_bytes();
    let s1 = an.geodesic_solver(&GeodesicParams::default()).unwrap();
    for v in [0, 5, n - 1] {
        let g = an.field(&geodesic(Some(v), vec![], 1.0)).unwrap();
        assert_eq!(g.values[v], 0.0);
    }
    let set = an.field(&geodesic(None, vec![0, n - 1], 1.0)).unwrap();
    assert_eq!(set.marks, vec![0, n - 1]);
    assert_eq!(set.request.source(), Some(0));
    assert_eq!(
        set.values,
        s1.distance(&[0.into(), (n - 1).into()]).unwrap()
    );
    assert!(Arc::ptr_eq(
        &s1,
        &an.geodesic_solver(&GeodesicParams::default()).unwrap()
    ));
    assert_eq!(lock(&an.geodesic).len(), 1);
    assert_eq!(an.memory_bytes(), before);
    // Another m is another solver (kept beside the first).
    let m2 = an.field(&geodesic(Some(src), vec![], 4.0)).unwrap();
    assert_ne!(m2.values, f.values);
    assert_eq!(lock(&an.geodesic).len(), 2);
    assert!(an.memory_bytes() > before);
    // Critical points: the source is the one minimum.
    let rep = an.field_critical_points(&f).unwrap();
    assert!(rep.points.minima.contains(&src), "{:?}", rep.points.minima);
}

#[test]
fn a_geodesic_distance_says_which_components_it_cannot_reach() {
    let (mesh, n0) = two_copies("sphere:res=2");
    let an = Analysis::new(mesh, AnalysisOptions::default());
    let f = an.field(&geodesic(Some(3), vec![], 1.0)).unwrap();
    assert!(f.values[..n0].iter().all(|v| v.is_finite()));
    assert!(f.values[n0..].iter().all(|&v| v == f64::INFINITY));
    let other = an.topology().vertex_component[n0];
    assert_eq!(f.unreachable, vec![other]);
    assert_eq!(f.unreachable_vertices, n0);
    let msg = f.unreachable_message().unwrap();
    assert!(
        msg.starts_with(&format!("{n0} of {} vertices cannot be reached", 2 * n0))
            && msg.contains("1 component without a source")
            && msg.contains("infinite"),
        "{msg}"
    );
    let (lo, hi) = f.finite_range().unwrap();
    assert!(lo == 0.0 && hi.is_finite() && hi > 0.0);
    // No critical point on the unreachable sphere; the reached one checks alone.
    let rep = an.field_critical_points(&f).unwrap();
    assert_eq!(rep.left_out.excluded_components, vec![other]);
    assert!(rep.points.minima.iter().all(|&v| v < n0));
    assert!(rep.points.maxima.iter().all(|&v| v < n0));
    assert!(rep.points.saddles.iter().all(|&(v, _)| v < n0));
    assert!(rep.check.holds && rep.chi == 2, "{rep:?}");
    // The library's picture path leaves it out as well.
    let p = crate::fields::persistence::simplified_critical_points(an.mesh(), &f.values).unwrap();
    assert!(
        p.shown
            .minima
            .iter()
            .chain(&p.shown.maxima)
            .all(|&v| v < n0)
    );
    // A source on each: every value finite.
    let both = an.field(&geodesic(Some(3), vec![n0 + 3], 1.0)).unwrap();
    assert!(both.values.iter().all(|v| v.is_finite()));
    assert!(both.unreachable.is_empty());
    close(&both.values[..n0], &f.values[..n0], 1e-12);
}

#[test]
fn geodesic_errors_name_the_source_and_the_laplacian() {
    let t = build_str("sphere:res=1").unwrap();
    let n = t.n_vertices();
    let mut pos = t.positions().to_vec();
    pos.push([5.0, 5.0, 5.0]); // a vertex in no triangle
    let an = Analysis::new(
        Mesh::new(pos, t.triangles().to_vec()).unwrap(),
        AnalysisOptions::default(),
    );
    let req = |source: usize, sources: Vec<usize>| geodesic(Some(source), sources, 1.0);
    let e = an.field(&req(n + 1, vec![])).unwrap_err();
    assert!(
        e.to_string()
            .starts_with(&format!("source {} is out of range", n + 1)),
        "{e}"
    );
    let e = an.field(&req(0, vec![n + 7])).unwrap_err();
    assert!(e.to_string().starts_with("sources"), "{e}");
    let e = an.field(&req(n, vec![])).unwrap_err();
    assert!(
        e.to_string()
            .contains(&format!("source vertex {n} belongs to no triangle")),
        "{e}"
    );
    // The loose vertex is unreachable from any source: said, never a number.
    let f = an.field(&req(0, vec![])).unwrap();
    assert_eq!(f.values[n], f64::INFINITY);
    assert!(
        f.unreachable_message()
            .unwrap()
            .contains("vertices in no triangle")
    );
    let uniform = Analysis::new(
        build_str("sphere:res=1").unwrap(),
        AnalysisOptions {
            laplacian: Laplacian::Uniform,
            ..Default::default()
        },
    );
    let e = uniform.field(&req(0, vec![])).unwrap_err();
    assert!(e.to_string().contains("cotangent Laplacian"), "{e}");
}
