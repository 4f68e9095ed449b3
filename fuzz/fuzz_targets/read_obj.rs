//! `io::read_mesh_from_bytes` on raw bytes named `fuzz.obj`: a clean error naming the
//! file, or a valid mesh that survives a write-then-read round trip.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    spectral_mesh_fuzz::read_and_check(data, "fuzz.obj");
});
