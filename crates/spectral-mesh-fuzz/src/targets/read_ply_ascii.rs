//! `io::read_mesh_from_bytes` on raw bytes named `fuzz.ply` (header and body as the fuzzer
//! writes them; the seeds are ASCII PLY files).

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    crate::read_and_check(data, "fuzz.ply");
}
