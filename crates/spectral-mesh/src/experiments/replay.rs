//! What an experiment file needs from the library: a content hash of a mesh, so that a
//! replay can tell whether it runs on the same mesh as the original run.

use crate::mesh::Mesh;

/// The blake3 hash (64 lowercase hex digits) of a mesh: the vertex positions as
/// little-endian `f64` bytes (x, y, z per vertex, in vertex order), followed by the
/// triangles as little-endian `u64` bytes (three corners per triangle, in order).
///
/// Two meshes have the same hash exactly when they have the same vertex count, the same
/// coordinates bit for bit and the same triangles in the same order (up to blake3
/// collisions); anything else, even `0.0` versus `-0.0`, changes it.
pub fn mesh_hash(mesh: &Mesh) -> String {
    mesh.content_hash()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> Mesh {
        Mesh::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2]],
        )
        .unwrap()
    }

    #[test]
    fn hash_is_the_blake3_of_the_documented_bytes_and_sees_every_change() {
        let m = tri();
        let mut bytes = Vec::new();
        for p in m.positions() {
            for c in p {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        for t in m.triangles() {
            for &v in t {
                bytes.extend_from_slice(&(v as u64).to_le_bytes());
            }
        }
        assert_eq!(mesh_hash(&m), blake3::hash(&bytes).to_hex().to_string());
        assert_eq!(mesh_hash(&m).len(), 64);
        let moved = Mesh::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 1e-300]],
            vec![[0, 1, 2]],
        )
        .unwrap();
        assert_ne!(mesh_hash(&m), mesh_hash(&moved));
        let flipped = Mesh::new(m.positions().to_vec(), vec![[0, 2, 1]]).unwrap();
        assert_ne!(mesh_hash(&m), mesh_hash(&flipped));
    }
}
