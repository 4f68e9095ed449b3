//! The point-cloud Laplacian on small clouds drawn from the input
//! (`operators::point_cloud::point_cloud_laplacian`, `operators/point_cloud.rs` and the
//! robust pipeline of `operators/robust.rs`): up to 64 points on a coarse integer grid
//! (coincident, collinear and coplanar neighbourhoods are common) times a scale, optional
//! normals, and the parameters (neighbours 2..=17, normal source, union rule) picked by
//! the first bytes. The function promises an error only for parameters out of range, so
//! it must return `Ok`: `S` and `B` are `n x n`, `B` diagonal and non-negative; for scales
//! within `1e-30..1e30` both are finite, `S` symmetric with zero row sums (to rounding)
//! and a non-negative diagonal. (Not up to `1e100`, the range of the shape specs: at
//! `1e90` the operator has non-finite entries, a known open finding, RELIABILITY.md.)

use arbitrary::{Arbitrary, Unstructured};
use spectral_mesh::mesh::PointCloud;
use spectral_mesh::operators::point_cloud::{
    NormalSource, PointCloudParams, TriangleUnion, point_cloud_laplacian,
};

const MAX_POINTS: usize = 64;

fn cloud(u: &mut Unstructured<'_>) -> Option<(PointCloud, i32)> {
    let scale_exp = i32::from(i8::arbitrary(u).ok()?).clamp(-100, 100) * 3;
    let scale = 10f64.powi(scale_exp);
    let n = usize::from(u8::arbitrary(u).ok()?) % MAX_POINTS + 1;
    let with_normals = bool::arbitrary(u).ok()?;
    let mut pos = Vec::with_capacity(n);
    let mut nrm = Vec::with_capacity(n);
    for _ in 0..n {
        let p = <[i8; 3]>::arbitrary(u).ok()?;
        pos.push(p.map(|c| f64::from(c) * scale));
        if with_normals {
            nrm.push(<[i8; 3]>::arbitrary(u).ok()?.map(f64::from));
        }
    }
    let cloud = PointCloud::new(pos, with_normals.then_some(nrm)).ok()?;
    Some((cloud, scale_exp))
}

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    let mut u = Unstructured::new(data);
    let Ok(pick) = u8::arbitrary(&mut u) else {
        return;
    };
    let params = PointCloudParams {
        neighbors: 2 + usize::from(pick & 0x0f),
        normals: if pick & 0x10 != 0 {
            NormalSource::FromCloud
        } else {
            NormalSource::Estimate
        },
        union: [
            TriangleUnion::Consensus,
            TriangleUnion::ConsensusOnly,
            TriangleUnion::Multiplicity,
            TriangleUnion::Interleaved,
        ][usize::from(pick >> 5) % 4],
        ..PointCloudParams::default()
    };
    let Some((cloud, scale_exp)) = cloud(&mut u) else {
        return;
    };
    let n = cloud.n_points();
    let l = point_cloud_laplacian(&cloud, &params)
        .unwrap_or_else(|e| panic!("valid parameters {params:?} refused: {e}"));
    let (s, b) = (&l.stiffness, &l.mass);
    assert_eq!((s.nrows(), s.ncols()), (n, n), "S shape");
    assert_eq!((b.nrows(), b.ncols()), (n, n), "B shape");
    assert!(b.is_diagonal(), "B is not diagonal");
    assert!(
        b.diag().iter().all(|&m| m.is_nan() || m >= 0.0),
        "negative mass: {:?}",
        b.diag()
    );
    if scale_exp.abs() > 30 {
        return;
    }
    assert!(
        s.values().iter().chain(b.values()).all(|v| v.is_finite()),
        "non-finite entry in S or B (scale 1e{scale_exp})"
    );
    let max = s.max_abs();
    let tol = 1e-9 * max.max(f64::MIN_POSITIVE);
    assert!(
        s.asymmetry() <= tol,
        "S not symmetric: {} (max {max})",
        s.asymmetry()
    );
    for (i, r) in s.row_sums().iter().enumerate() {
        assert!(
            r.abs() <= 1e-8 * max.max(f64::MIN_POSITIVE),
            "row {i} of S sums to {r} (max {max})"
        );
    }
    assert!(
        s.diag().iter().all(|&d| d >= -tol),
        "negative diagonal of S"
    );
}
