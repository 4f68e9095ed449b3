//! Polygon triangulation used by every reader.

use crate::mesh::{cross, norm, normalize, plane_coordinates, sub};

/// Largest polygon triangulated by ear clipping; bigger ones get a fan.
const MAX_EAR_CLIPPING: usize = 64;

/// Splits polygon `poly` (vertex indices into `positions`, at least 3, all distinct) into
/// `poly.len() - 2` triangles appended to `out`, keeping the polygon's winding.
///
/// The rule:
/// 1. The polygon is projected onto the plane orthogonal to its Newell normal (its best-fit
///    plane for a planar or nearly planar polygon), so its projection winds positively.
/// 2. Ear clipping: a corner is an ear when it is strictly convex and no other remaining
///    corner lies inside or on its triangle. Among the ears the one whose triangle has the
///    largest smallest angle is cut first (so a convex quad is split along the diagonal
///    that gives the better triangles, and a non-convex polygon never gets a triangle
///    outside itself).
/// 3. If no ear exists (a self-intersecting or degenerate polygon), the most convex corner
///    is cut; if no corner is convex at all, the first remaining corner is.
///
/// A polygon whose Newell normal is zero (no usable plane) or with more than 64 corners
/// (ear clipping as done here costs O(k^3)) is fan-triangulated from its first vertex
/// instead; the function then returns `false` (the readers turn that into a warning). Otherwise it returns `true`.
pub fn triangulate_polygon(
    positions: &[[f64; 3]],
    poly: &[usize],
    out: &mut Vec<[usize; 3]>,
) -> bool {
    let k = poly.len();
    if k < 3 {
        return false;
    }
    if k == 3 {
        out.push([poly[0], poly[1], poly[2]]);
        return true;
    }
    let fan = |out: &mut Vec<[usize; 3]>| {
        for i in 1..k - 1 {
            out.push([poly[0], poly[i], poly[i + 1]]);
        }
    };
    if k > MAX_EAR_CLIPPING {
        fan(out);
        return false;
    }
    // Newell normal.
    let mut nrm = [0.0; 3];
    for i in 0..k {
        let a = positions[poly[i]];
        let b = positions[poly[(i + 1) % k]];
        nrm[0] += (a[1] - b[1]) * (a[2] + b[2]);
        nrm[1] += (a[2] - b[2]) * (a[0] + b[0]);
        nrm[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    let mut extent = 0.0f64;
    for i in 0..k {
        extent = extent.max(norm(sub(positions[poly[i]], positions[poly[0]])));
    }
    let nn = norm(nrm);
    if nn.is_nan() || nn <= 1e-14 * extent * extent {
        fan(out);
        return false;
    }
    let n = normalize(nrm);
    // u orthogonal to n, v = n x u: (u, v, n) right-handed, so the projection winds positively.
    let helper = if n[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let u = normalize(cross(helper, n));
    let v = cross(n, u);
    let origin = positions[poly[0]];
    let pts = plane_coordinates(positions, poly, origin, [u, v]);
    let eps = 1e-14 * extent * extent;
    let mut rem: Vec<usize> = (0..k).collect();
    while rem.len() > 3 {
        let r = rem.len();
        let mut best: Option<(usize, f64)> = None;
        let mut most_convex: Option<(usize, f64)> = None;
        for j in 0..r {
            let (a, b, c) = (rem[(j + r - 1) % r], rem[j], rem[(j + 1) % r]);
            let turn = cross2(pts[a], pts[b], pts[c]);
            if most_convex.is_none_or(|(_, t)| turn > t) {
                most_convex = Some((j, turn));
            }
            if turn <= eps {
                continue;
            }
            let blocked = rem.iter().any(|&o| {
                o != a && o != b && o != c && in_triangle(pts[o], pts[a], pts[b], pts[c])
            });
            if blocked {
                continue;
            }
            let q = min_angle_cos_free(pts[a], pts[b], pts[c]);
            if best.is_none_or(|(_, bq)| q > bq) {
                best = Some((j, q));
            }
        }
        let j = match (best, most_convex) {
            (Some((j, _)), _) => j,
            (None, Some((j, t))) if t > 0.0 => j,
            _ => 0,
        };
        let (a, b, c) = (rem[(j + r - 1) % r], rem[j], rem[(j + 1) % r]);
        out.push([poly[a], poly[b], poly[c]]);
        rem.remove(j);
    }
    out.push([poly[rem[0]], poly[rem[1]], poly[rem[2]]]);
    true
}

fn cross2(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0])
}

/// Closed triangle test for a positively wound triangle.
fn in_triangle(p: [f64; 2], a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> bool {
    let s1 = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
    let s2 = (c[0] - b[0]) * (p[1] - b[1]) - (c[1] - b[1]) * (p[0] - b[0]);
    let s3 = (a[0] - c[0]) * (p[1] - c[1]) - (a[1] - c[1]) * (p[0] - c[0]);
    s1 >= 0.0 && s2 >= 0.0 && s3 >= 0.0
}

/// The smallest angle of triangle abc (radians).
fn min_angle_cos_free(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    let ang = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        let (x, y) = ([q[0] - p[0], q[1] - p[1]], [r[0] - p[0], r[1] - p[1]]);
        let cr = (x[0] * y[1] - x[1] * y[0]).abs();
        let d = x[0] * y[0] + x[1] * y[1];
        cr.atan2(d)
    };
    ang(a, b, c).min(ang(b, c, a)).min(ang(c, a, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Triangulates the polygon `poly` over the corners `xy` (in the plane z = 0) and checks
    /// that it gives `triangles` triangles, all wound as the polygon (counter-clockwise),
    /// whose areas add up to `area`: none leaves the polygon.
    fn check_triangulation(xy: &[[f64; 2]], poly: &[usize], triangles: usize, area: f64) {
        let p: Vec<[f64; 3]> = xy.iter().map(|&[x, y]| [x, y, 0.0]).collect();
        let mut out = Vec::new();
        assert!(triangulate_polygon(&p, poly, &mut out));
        assert_eq!(out.len(), triangles);
        let mut total = 0.0;
        for &t in &out {
            let a = cross(sub(p[t[1]], p[t[0]]), sub(p[t[2]], p[t[0]]));
            assert!(a[2] > 0.0, "every triangle keeps the winding: {t:?}");
            total += 0.5 * a[2];
        }
        assert!((total - area).abs() < 1e-12, "area {total}");
    }

    #[test]
    fn convex_quad_keeps_winding_and_area() {
        let square = [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]];
        check_triangulation(&square, &[0, 1, 2, 3], 2, 2.0);
    }

    #[test]
    fn non_convex_polygon_has_no_triangle_outside() {
        // An L shape (reflex corner at 3), started at the reflex corner so that a naive
        // fan would leave the shape.
        let l_shape = [
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [1.0, 1.0],
            [1.0, 2.0],
            [0.0, 2.0],
        ];
        check_triangulation(&l_shape, &[3, 4, 5, 0, 1, 2], 4, 3.0);
    }

    #[test]
    fn degenerate_polygon_falls_back_to_fan() {
        let p = vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [3.0, 0.0, 0.0]];
        let mut out = Vec::new();
        assert!(!triangulate_polygon(&p, &[0, 1, 2, 3], &mut out));
        assert_eq!(out, vec![[0, 1, 2], [0, 2, 3]]);
    }
}
