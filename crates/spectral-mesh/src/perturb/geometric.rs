//! Perturbations that move vertices and keep the connectivity: normal noise, global and
//! local scaling, rigid motions and a near-isometric bend. Their map is
//! [`SurfaceMap::Identity`] (correspondence by vertex index).

use super::rng::Rng;
use super::{PerturbError, Perturbed, SurfaceMap, finite, finite_point, finite3, positive};
use crate::mesh::{Mesh, add, dot, norm, scale as vscale, sub};

/// Gaussian noise along the vertex normals: vertex `i` moves by `z_i n_i` with
/// `z_i ~ N(0, sigma^2)`, `sigma = magnitude_rel * mean edge length`, and `n_i` the
/// area-weighted unit normal (a vertex with no normal does not move). Deterministic in
/// `seed`.
pub fn noise(mesh: &Mesh, magnitude_rel: f64, seed: u64) -> Result<Perturbed, PerturbError> {
    let magnitude_rel = finite("noise magnitude", magnitude_rel)?;
    if magnitude_rel < 0.0 {
        return Err(PerturbError::InvalidParameter {
            name: "noise magnitude",
            value: magnitude_rel.to_string(),
            reason: "must be >= 0 (a fraction of the mean edge length)".into(),
        });
    }
    let sigma = magnitude_rel * mesh.mean_edge_length();
    let normals = mesh.vertex_normals();
    let mut rng = Rng::new(seed);
    let positions: Vec<[f64; 3]> = mesh
        .positions()
        .iter()
        .zip(&normals)
        .map(|(&p, &n)| add(p, vscale(n, sigma * rng.normal())))
        .collect();
    Ok(Perturbed {
        mesh: Mesh::new(positions, mesh.triangles().to_vec())?,
        map: SurfaceMap::Identity,
        description: format!(
            "Gaussian noise along vertex normals, sigma = {magnitude_rel} x mean edge length = {sigma:.6e}, seed {seed}"
        ),
    })
}

/// The area-weighted centroid of the surface (the vertex mean when the area is zero).
pub fn surface_centroid(mesh: &Mesh) -> [f64; 3] {
    let areas = mesh.triangle_areas();
    let total: f64 = areas.iter().sum();
    if total > 0.0 {
        let mut c = [0.0; 3];
        for (t, &a) in areas.iter().enumerate() {
            let [p, q, r] = mesh.corners(t);
            c = add(c, vscale(add(add(p, q), r), a / 3.0));
        }
        vscale(c, 1.0 / total)
    } else {
        let n = mesh.n_vertices() as f64;
        let s = mesh.positions().iter().fold([0.0; 3], |c, &p| add(c, p));
        vscale(s, 1.0 / n)
    }
}

/// Uniform scaling by `alpha > 0` about the area-weighted centroid. Lengths scale by
/// `alpha`, areas by `alpha^2`, and the eigenvalues of (S, B) for any area-based mass by
/// `1 / alpha^2`.
pub fn scale(mesh: &Mesh, alpha: f64) -> Result<Perturbed, PerturbError> {
    let alpha = positive("scale factor", alpha)?;
    let c = surface_centroid(mesh);
    Ok(Perturbed {
        mesh: mesh.map_positions(|p| add(c, vscale(sub(p, c), alpha)))?,
        map: SurfaceMap::Identity,
        description: format!("uniform scaling by {alpha} about the centroid"),
    })
}

/// Smooth falloff used by [`local_scale`]: `(1 - x^2)^3` on `[0, 1]`, 0 beyond
/// (value 1 and zero slope at the centre, C^2 at `x = 1`).
fn falloff(x: f64) -> f64 {
    if x >= 1.0 {
        0.0
    } else {
        let s = 1.0 - x * x;
        s * s * s
    }
}

/// Local scaling about `center`: `p -> c + (p - c) (1 + (alpha - 1) w(|p - c| / radius))`
/// with the smooth falloff `w(x) = (1 - x^2)^3` (1 at the centre, 0 from `radius` on).
/// The radial map stays one-to-one for `0 < alpha < 2.6`; larger factors may fold the
/// surface and are rejected.
pub fn local_scale(
    mesh: &Mesh,
    center: [f64; 3],
    radius: f64,
    alpha: f64,
) -> Result<Perturbed, PerturbError> {
    let radius = positive("local scale radius", radius)?;
    let alpha = positive("local scale factor", alpha)?;
    finite_point(center)?;
    if alpha >= 2.6 {
        return Err(PerturbError::InvalidParameter {
            name: "local scale factor",
            value: alpha.to_string(),
            reason: "must be below 2.6 (larger factors fold the surface)".into(),
        });
    }
    let m = mesh.map_positions(|p| {
        let d = sub(p, center);
        let w = falloff(norm(d) / radius);
        if w == 0.0 {
            // Outside the ball: untouched, bit for bit.
            return p;
        }
        add(center, vscale(d, 1.0 + (alpha - 1.0) * w))
    })?;
    Ok(Perturbed {
        mesh: m,
        map: SurfaceMap::Identity,
        description: format!(
            "local scaling by {alpha} about ({}, {}, {}) with radius {radius} (falloff (1-x^2)^3)",
            center[0], center[1], center[2]
        ),
    })
}

/// The rotation matrix (rows) of angle `angle` (radians, right-handed) about the unit
/// vector `k`, by Rodrigues' formula `R = I + sin(a) K + (1 - cos(a)) K^2`.
pub fn rotation_matrix(k: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let (s, c) = angle.sin_cos();
    let v = 1.0 - c;
    let [x, y, z] = k;
    [
        [c + x * x * v, x * y * v - z * s, x * z * v + y * s],
        [y * x * v + z * s, c + y * y * v, y * z * v - x * s],
        [z * x * v - y * s, z * y * v + x * s, c + z * z * v],
    ]
}

/// A rigid motion: rotation by `angle` radians about the line through the origin with
/// direction `axis` (any non-zero vector; right-handed), then translation by
/// `translation`. Lengths, angles and areas are preserved, so S and B change only by
/// rounding.
pub fn rigid_motion(
    mesh: &Mesh,
    axis: [f64; 3],
    angle: f64,
    translation: [f64; 3],
) -> Result<Perturbed, PerturbError> {
    let angle = finite("rotation angle", angle)?;
    finite3(["axis x", "axis y", "axis z"], axis)?;
    finite3(
        ["translation x", "translation y", "translation z"],
        translation,
    )?;
    let len = norm(axis);
    if len == 0.0 || !len.is_finite() {
        return Err(PerturbError::InvalidParameter {
            name: "rotation axis",
            value: format!("({}, {}, {})", axis[0], axis[1], axis[2]),
            reason: "must be a non-zero vector".into(),
        });
    }
    let k = vscale(axis, 1.0 / len);
    let r = rotation_matrix(k, angle);
    let m = mesh.map_positions(|p| add([dot(r[0], p), dot(r[1], p), dot(r[2], p)], translation))?;
    Ok(Perturbed {
        mesh: m,
        map: SurfaceMap::Identity,
        description: format!(
            "rigid motion: rotation by {:.6} degrees about axis ({:.6}, {:.6}, {:.6}) through the origin, then translation by ({}, {}, {})",
            angle.to_degrees(),
            k[0],
            k[1],
            k[2],
            translation[0],
            translation[1],
            translation[2]
        ),
    })
}

/// A near-isometric bend of an elongated shape by a total angle `angle` (radians,
/// `|angle| <= 2 pi`; the sign picks the side).
///
/// `axis` (0 = x, 1 = y, 2 = z) is the direction that gets bent; `None` takes the longest
/// side of the bounding box. The shape curls in the plane spanned by `axis` and the
/// shortest remaining bounding-box direction `d`; the third direction is unchanged. With
/// `L` the extent along `axis` and `R = L / angle`, a point at offset `s` along `axis` and
/// `h` along `d` from the box centre goes to angle `phi = s / R` on a circle:
/// `s' = (R - h) sin(phi)`, `h' = R - (R - h) cos(phi)`. The mid-plane `h = 0` is mapped
/// isometrically (its lengths along `axis` are kept exactly), other points are stretched
/// by `1 - h / R`, which is first order in the thickness-to-radius ratio. Points with
/// `h > R` would fold; keep the bend gentle for thick shapes.
pub fn bend(mesh: &Mesh, axis: Option<usize>, angle: f64) -> Result<Perturbed, PerturbError> {
    let angle = finite("bend angle", angle)?;
    if angle.abs() > std::f64::consts::TAU {
        return Err(PerturbError::InvalidParameter {
            name: "bend angle",
            value: format!("{} degrees", angle.to_degrees()),
            reason: "must be at most 360 degrees in magnitude".into(),
        });
    }
    let (lo, hi) = mesh.bounding_box();
    let ext = sub(hi, lo);
    let a = match axis {
        Some(a) if a < 3 => a,
        Some(a) => {
            return Err(PerturbError::InvalidParameter {
                name: "bend axis",
                value: a.to_string(),
                reason: "must be 0 (x), 1 (y) or 2 (z)".into(),
            });
        }
        None => (0..3)
            .max_by(|&i, &j| ext[i].total_cmp(&ext[j]).then(j.cmp(&i)))
            .unwrap_or(0),
    };
    let (o1, o2) = ((a + 1) % 3, (a + 2) % 3);
    let d = if ext[o1] <= ext[o2] { o1 } else { o2 };
    let len = ext[a];
    let axis_name = ["x", "y", "z"];
    let description = format!(
        "bend by {:.6} degrees along {} (curling toward {})",
        angle.to_degrees(),
        axis_name[a],
        axis_name[d]
    );
    if angle == 0.0 || len == 0.0 {
        return Ok(Perturbed {
            mesh: mesh.clone(),
            map: SurfaceMap::Identity,
            description,
        });
    }
    let r = len / angle;
    let u0 = 0.5 * (lo[a] + hi[a]);
    let w0 = 0.5 * (lo[d] + hi[d]);
    let m = mesh.map_positions(|p| {
        let s = p[a] - u0;
        let h = p[d] - w0;
        let phi = s / r;
        let (sn, cs) = phi.sin_cos();
        let mut q = p;
        q[a] = u0 + (r - h) * sn;
        q[d] = w0 + r - (r - h) * cs;
        q
    })?;
    Ok(Perturbed {
        mesh: m,
        map: SurfaceMap::Identity,
        description,
    })
}
