//! `io::read_mesh_from_bytes` on raw bytes named `fuzz.off`: a clean error naming the
//! file, or a valid mesh that survives a write-then-read round trip.

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    crate::read_and_check(data, "fuzz.off");
}
