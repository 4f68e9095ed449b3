//! Point clouds as the input of an analysis.
//!
//! An [`super::Analysis`] of a point cloud uses the point-cloud Laplacian
//! ([`crate::operators::point_cloud`]) as its operators, and for everything that needs a
//! connectivity (critical points, level sets, segmentation, harmonic maps' components,
//! pictures) the **triangle union** that Laplacian was built on: the distinct triangles of
//! its local Delaunay stars (the consensus triangulation, plus the patches of its holes),
//! oriented consistently where they form a manifold. That set, not the k-nearest-neighbour
//! graph, is chosen because:
//! - it *is* the connectivity of `S` (its non-zeros are its edges and the intrinsic flips
//!   of the robust pipeline stay inside its components), so the pieces the eigensolver
//!   deflates are exactly the components the Euler check counts;
//! - critical points need the cyclic order of a point's neighbours (a saddle is a point
//!   whose link changes sign four or more times), which triangles give and a graph does not;
//! - level sets are drawn through triangles;
//! - the k-nearest-neighbour relation is not symmetric and joins points across thin gaps
//!   (two sheets closer than the sampling), which the local triangulations avoid.
//!
//! **Critical points on a cloud** are therefore those of the piecewise-linear
//! interpolation of the field on this triangle union, a surface reconstructed locally from
//! the points. On a clean sampling of a closed surface the union is a closed manifold and
//! the Euler check holds as on a mesh; on noisy scans it may have holes and non-manifold
//! edges (patched with the local triangles), where points are reported as non-manifold and
//! the check can fail: read it as a check of the reconstruction as much as of the field.
//! Points in no triangle ([`crate::operators::point_cloud::PointCloudStats::isolated_points`]) are not
//! classified.

use std::collections::HashMap;

use crate::io::Input;
use crate::mesh::{Mesh, PointCloud};
use crate::operators::PointCloudParams;

/// What an analysis is of: a triangle mesh, or a point cloud with the parameters of its
/// Laplacian. Built from what [`crate::io::read_input`] read with `From`.
#[derive(Debug, Clone)]
pub enum AnalysisInput {
    /// A triangle mesh (any discretization applies).
    Mesh(Mesh),
    /// A point cloud (only the point-cloud Laplacian applies: [`crate::Laplacian::Robust`]).
    Points {
        /// The points (and their normals, if any).
        cloud: PointCloud,
        /// Parameters of the point-cloud Laplacian.
        params: PointCloudParams,
    },
}

impl AnalysisInput {
    /// Number of vertices or points.
    pub fn n(&self) -> usize {
        match self {
            AnalysisInput::Mesh(m) => m.n_vertices(),
            AnalysisInput::Points { cloud, .. } => cloud.n_points(),
        }
    }

    /// True for a point cloud.
    pub fn is_points(&self) -> bool {
        matches!(self, AnalysisInput::Points { .. })
    }

    /// `"mesh"` or `"point cloud"`, for messages.
    pub fn kind_name(&self) -> &'static str {
        match self {
            AnalysisInput::Mesh(_) => "mesh",
            AnalysisInput::Points { .. } => "point cloud",
        }
    }

    /// The content hash of the input ([`Mesh::content_hash`] or
    /// [`PointCloud::content_hash`]).
    pub fn content_hash(&self) -> String {
        match self {
            AnalysisInput::Mesh(m) => m.content_hash(),
            AnalysisInput::Points { cloud, .. } => cloud.content_hash(),
        }
    }

    /// The mesh, or `None` for a point cloud.
    pub fn mesh(&self) -> Option<&Mesh> {
        match self {
            AnalysisInput::Mesh(m) => Some(m),
            AnalysisInput::Points { .. } => None,
        }
    }
}

impl From<Mesh> for AnalysisInput {
    fn from(m: Mesh) -> Self {
        AnalysisInput::Mesh(m)
    }
}

impl From<PointCloud> for AnalysisInput {
    /// The cloud with the default [`PointCloudParams`].
    fn from(cloud: PointCloud) -> Self {
        AnalysisInput::Points {
            cloud,
            params: PointCloudParams::default(),
        }
    }
}

impl From<Input> for AnalysisInput {
    /// A mesh as read, or a point cloud with the default [`PointCloudParams`].
    fn from(i: Input) -> Self {
        match i {
            Input::Mesh(m) => AnalysisInput::Mesh(m.mesh),
            Input::Points(p) => p.cloud.into(),
        }
    }
}

/// The connectivity mesh of a cloud: its points and the triangle union, oriented
/// consistently across every edge shared by exactly two triangles. `None` when there is
/// no triangle.
pub(crate) fn connectivity_mesh(
    cloud: &PointCloud,
    mut triangles: Vec<[usize; 3]>,
) -> Option<Mesh> {
    orient(&mut triangles);
    Mesh::new(cloud.positions().to_vec(), triangles).ok()
}

/// Flips triangles so that the two triangles of every manifold edge traverse it in
/// opposite directions (breadth first from the lowest triangle of each component; a
/// non-orientable component keeps some inconsistent edges).
fn orient(tris: &mut [[usize; 3]]) {
    let key = |a: usize, b: usize| (a.min(b), a.max(b));
    let mut on_edge: HashMap<(usize, usize), (u32, u32, u8)> =
        HashMap::with_capacity(tris.len() * 3 / 2 + 1);
    for (t, tri) in tris.iter().enumerate() {
        for k in 0..3 {
            let e = on_edge
                .entry(key(tri[k], tri[(k + 1) % 3]))
                .or_insert((u32::MAX, u32::MAX, 0));
            match e.2 {
                0 => e.0 = t as u32,
                1 => e.1 = t as u32,
                _ => {}
            }
            e.2 = e.2.saturating_add(1);
        }
    }
    let mut done = vec![false; tris.len()];
    let mut stack = Vec::new();
    for start in 0..tris.len() {
        if done[start] {
            continue;
        }
        done[start] = true;
        stack.push(start);
        while let Some(t) = stack.pop() {
            let tri = tris[t];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let Some(&(t0, t1, count)) = on_edge.get(&key(a, b)) else {
                    continue;
                };
                if count != 2 {
                    continue;
                }
                let u = (if t0 as usize == t { t1 } else { t0 }) as usize;
                if u >= tris.len() || done[u] {
                    continue;
                }
                let tu = tris[u];
                if (0..3).any(|j| tu[j] == a && tu[(j + 1) % 3] == b) {
                    tris[u].swap(1, 2);
                }
                done[u] = true;
                stack.push(u);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::topology::Topology;

    #[test]
    fn orientation_is_made_consistent() {
        // An octahedron with every other triangle flipped.
        let (pos, mut tris) = crate::test_support::octahedron();
        for t in tris.iter_mut().step_by(2) {
            t.swap(0, 1);
        }
        let before = Topology::new(&Mesh::new(pos.clone(), tris.clone()).unwrap());
        assert!(before.inconsistently_oriented_edges > 0);
        orient(&mut tris);
        let after = Topology::new(&Mesh::new(pos, tris).unwrap());
        assert_eq!(after.inconsistently_oriented_edges, 0);
    }

    /// `n` points on the unit sphere centred at `c` (Fibonacci lattice).
    fn fibonacci(n: usize, c: [f64; 3]) -> Vec<[f64; 3]> {
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|i| {
                let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let r = (1.0 - y * y).sqrt();
                let th = golden * i as f64;
                [c[0] + r * th.cos(), c[1] + y, c[2] + r * th.sin()]
            })
            .collect()
    }

    fn robust() -> crate::analysis::AnalysisOptions {
        crate::analysis::AnalysisOptions {
            laplacian: crate::Laplacian::Robust,
            normalize: false,
            ..Default::default()
        }
    }

    #[test]
    fn a_cloud_of_two_spheres_is_analysed_like_a_mesh() {
        use crate::analysis::{Analysis, FieldRequest};
        let mut pts = fibonacci(800, [0.0; 3]);
        pts.extend(fibonacci(800, [4.0, 0.0, 0.0]));
        let cloud = PointCloud::new(pts, None).unwrap();
        let an = Analysis::from_input(cloud, robust()).unwrap();
        assert!(an.is_point_cloud());
        assert_eq!(an.n(), 1600);
        // The connectivity: two closed spheres, consistently oriented.
        let topo = an.topology();
        assert_eq!(topo.n_components(), 2);
        assert!(
            topo.components
                .iter()
                .all(|c| c.closed && c.euler_characteristic == 2)
        );
        assert_eq!(topo.inconsistently_oriented_edges, 0);
        // Two zero eigenvalues, then l = 1 (x 6, two spheres) near l(l+1) = 2.
        let b = an
            .basis(8, &mut |_| {}, &crate::CancelToken::new())
            .unwrap();
        assert!(
            b.values[0].abs() < 1e-8 && b.values[1].abs() < 1e-8,
            "{:?}",
            b.values
        );
        for v in &b.values[2..8] {
            assert!((v - 2.0).abs() < 0.02 * 2.0, "{:?}", b.values);
        }
        // A field and its critical points with the Euler check on each sphere.
        let f = an.field(&FieldRequest::default_with_k(20)).unwrap();
        assert!(f.values.iter().all(|v| v.is_finite()));
        let e = an
            .field(&FieldRequest::Eigenfunction { index: 2, k: 8 })
            .unwrap();
        let report = an.critical_points(&e.values).unwrap();
        assert!(report.check.holds, "{report:?}");
        let spacing = an.point_spacing().unwrap();
        assert!(spacing > 0.05 && spacing < 0.2, "{spacing}");
    }

    #[test]
    fn a_cloud_refuses_the_discretizations_that_need_triangles_by_name() {
        use crate::analysis::{Analysis, AnalysisError, AnalysisOptions};
        let cloud = PointCloud::new(fibonacci(100, [0.0; 3]), None).unwrap();
        let e = Analysis::from_input(cloud.clone(), AnalysisOptions::default()).unwrap_err();
        assert_eq!(
            e,
            AnalysisError::NotForPoints {
                laplacian: crate::Laplacian::Fem
            }
        );
        assert!(e.to_string().contains("point cloud"), "{e}");
        let line: Vec<[f64; 3]> = (0..10).map(|i| [i as f64, 0.0, 0.0]).collect();
        let e = Analysis::from_input(PointCloud::new(line, None).unwrap(), robust()).unwrap_err();
        assert_eq!(e, AnalysisError::NoTriangles { n: 10 });
        // A mesh goes through the same constructor.
        let m = crate::shapes::build_str("sphere:res=1").unwrap();
        let an = Analysis::from_input(m, AnalysisOptions::default()).unwrap();
        assert!(!an.is_point_cloud() && an.point_spacing().is_none());
    }
}
