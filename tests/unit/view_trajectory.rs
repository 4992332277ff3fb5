//! The tests of `src/cli/view/trajectory.rs`, formerly its `#[cfg(test)]` module (tests/unit/mod.rs).

use urdyn::cli::view::{FrameSampler, MAX_POSE_BYTES};

#[test]
fn sampler_keeps_one_row_a_frame_interval() {
    // Rows every millisecond for 1 s: the first row at or after each 1/60 s.
    let mut s = FrameSampler::new(1.0, 100);
    let kept: Vec<usize> = (0..=1000).filter(|&k| s.take(k as f64 * 1e-3)).collect();
    let want: Vec<usize> = (0..=60)
        .map(|j| (j as f64 * 1000.0 / 60.0 - 1e-9).ceil() as usize)
        .collect();
    assert_eq!(kept, want);
    // A long run at 1 kB a frame: the poses stay within MAX_POSE_BYTES.
    let mut s = FrameSampler::new(1e4, 1000);
    let n = (0..=1_000_000).filter(|&k| s.take(k as f64 * 1e-2)).count();
    assert!(
        n * 1000 <= MAX_POSE_BYTES && n * 1000 > MAX_POSE_BYTES * 9 / 10,
        "{n}"
    );
}
