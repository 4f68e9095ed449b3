//! `io::read_mesh_from_bytes` on raw bytes named `fuzz.stl` (the seeds are ASCII STL files;
//! a binary one is recognised by its size).

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    crate::read_and_check(data, "fuzz.stl");
}
