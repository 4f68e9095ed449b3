//! Peak resident memory of this process, for the rows of a batch (Linux: `VmHWM` of
//! `/proc/self/status`, reset through `/proc/self/clear_refs`; elsewhere unknown).

/// Resets the peak to the current resident size (Linux 4.0 and later; silently nothing
/// elsewhere).
pub fn reset_peak() {
    let _ = std::fs::write("/proc/self/clear_refs", b"5");
}

/// The peak resident size since the last [`reset_peak`] (or the process start), in bytes.
pub fn peak_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line
        .trim_start_matches("VmHWM:")
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kb * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_peak_follows_a_large_allocation() {
        let Some(before) = peak_bytes() else {
            eprintln!("SKIPPED: no /proc/self/status");
            return;
        };
        // black_box: an optimized build would otherwise drop the unused allocation.
        let big = std::hint::black_box(vec![1u8; 64 << 20]);
        let after = peak_bytes().unwrap();
        assert!(after >= before && after >= 64 << 20, "{before} -> {after}");
        drop(big);
    }
}
