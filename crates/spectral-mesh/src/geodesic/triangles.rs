//! The triangles that carry the gradient and the divergence of the heat method, each laid
//! out in its own plane from its edge lengths.

use crate::mesh::{Mesh, norm, sub};
use crate::operators::stiffness::{double_area_from_lengths, half_cotangents};

/// One triangle: vertices, edge vectors in the triangle's plane and half cotangents.
#[derive(Debug, Clone, Copy)]
struct Frame {
    /// Vertices `v0, v1, v2` (counter-clockwise in the layout).
    v: [usize; 3],
    /// `e[k] = p_{k+1} - p_k` in the layout.
    e: [[f64; 2]; 3],
    /// `w[k] = cot(angle at corner k) / 2 * scale`: the weight of the edge opposite `k`.
    w: [f64; 3],
}

/// Every non-degenerate triangle of a triangulation, laid out in the plane.
#[derive(Debug, Clone, Default)]
pub(super) struct FaceFrames {
    frames: Vec<Frame>,
}

impl FaceFrames {
    /// The input triangles of `mesh`, with the half cotangents of the cotangent stiffness
    /// (degenerate triangles, which give S nothing, are left out).
    pub fn from_mesh(mesh: &Mesh) -> Self {
        let frames = (0..mesh.n_triangles())
            .filter_map(|t| {
                let p = mesh.corners(t);
                let c = half_cotangents(p)?;
                let l = [
                    norm(sub(p[1], p[0])),
                    norm(sub(p[2], p[1])),
                    norm(sub(p[0], p[2])),
                ];
                let e = layout(l)?;
                Some(Frame {
                    v: mesh.triangles()[t],
                    e,
                    w: c,
                })
            })
            .collect();
        Self { frames }
    }

    /// Triangles given by vertices and edge lengths `[|v0 v1|, |v1 v2|, |v2 v0|]` (an
    /// intrinsic triangulation); weights times `scale`. The half cotangents are those of
    /// [`crate::operators::robust`] (zero for a triangle with area at rounding level, which
    /// is then left out).
    pub fn from_lengths(vertices: &[[usize; 3]], lengths: &[[f64; 3]], scale: f64) -> Self {
        let frames = vertices
            .iter()
            .zip(lengths)
            .filter_map(|(&v, &l)| {
                let dbl = double_area_from_lengths(l);
                let sq = l[0] * l[0] + l[1] * l[1] + l[2] * l[2];
                if dbl.is_nan() || dbl <= f64::EPSILON * sq {
                    return None;
                }
                // Corner k is opposite the edge of length l[(k + 1) % 3].
                let w = std::array::from_fn(|k| {
                    let a = l[(k + 1) % 3];
                    let b = l[(k + 2) % 3];
                    let d = l[k];
                    (b * b + d * d - a * a) / dbl / 4.0 * scale
                });
                Some(Frame {
                    v,
                    e: layout(l)?,
                    w,
                })
            })
            .collect();
        Self { frames }
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.frames.len() * std::mem::size_of::<Frame>()
    }

    /// Writes into `div` (zeroed first) the integrated divergence of `X = grad u / |grad u|`
    /// (zero in a triangle where `grad u = 0`):
    /// `div_i = sum of w_ij (p_j - p_i) . X` over the edges `i -> j` of each triangle;
    /// for up to `W` columns at once, stored by rows (`u[i][c]`: column `c` at vertex `i`),
    /// so that each triangle is read once for all of them. Every column gets the same
    /// arithmetic, in the same order, as it would alone.
    pub fn normalized_divergence_rows<const W: usize>(&self, u: &[[f64; W]], div: &mut [[f64; W]]) {
        for d in div.iter_mut() {
            *d = [0.0; W];
        }
        for f in &self.frames {
            let mut g0 = [0.0f64; W];
            let mut g1 = [0.0f64; W];
            for k in 0..3 {
                let o = f.e[(k + 1) % 3];
                let uk = &u[f.v[k]];
                for l in 0..W {
                    g0[l] -= uk[l] * o[1];
                    g1[l] += uk[l] * o[0];
                }
            }
            let mut x0 = [0.0f64; W];
            let mut x1 = [0.0f64; W];
            // Lanes where grad u = 0 keep X = 0 and so add (signed) zeros.
            for l in 0..W {
                let len = (g0[l] * g0[l] + g1[l] * g1[l]).sqrt();
                if len > 0.0 && len.is_finite() {
                    x0[l] = g0[l] / len;
                    x1[l] = g1[l] / len;
                }
            }
            for k in 0..3 {
                let wk = f.w[(k + 2) % 3];
                let e = f.e[k];
                let (a, b) = (f.v[k], f.v[(k + 1) % 3]);
                for l in 0..W {
                    let val = wk * (e[0] * x0[l] + e[1] * x1[l]);
                    div[a][l] += val;
                    div[b][l] -= val;
                }
            }
        }
    }
}

/// Edge vectors `p1 - p0, p2 - p1, p0 - p2` of the triangle with edge lengths
/// `[|p0 p1|, |p1 p2|, |p2 p0|]` laid out with `p0 = 0`, `p1` on the positive x axis and
/// `p2` above it. `None` for a zero first edge.
fn layout(l: [f64; 3]) -> Option<[[f64; 2]; 3]> {
    // Also refuses NaN.
    if l[0].is_nan() || l[0] <= 0.0 {
        return None;
    }
    let x = (l[0] * l[0] + l[2] * l[2] - l[1] * l[1]) / (2.0 * l[0]);
    let y = double_area_from_lengths(l) / l[0];
    Some([[l[0], 0.0], [x - l[0], y], [-x, -y]])
}
