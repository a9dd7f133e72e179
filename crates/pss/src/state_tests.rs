//! Unit tests of [`super::PssState`]: the state's own bookkeeping.

use super::*;

#[test]
fn fresh_state_reads_stable_uniforms() {
    let mut a = PssState::new(3, 9);
    a.begin();
    let first: Vec<f64> = (0..5).map(|_| a.next_sample()).collect();
    a.begin();
    let again: Vec<f64> = (0..5).map(|_| a.next_sample()).collect();
    assert_eq!(first, again);
    assert!(first.iter().all(|u| (0.0..1.0).contains(u)));
}

#[test]
fn streams_are_interleaved_and_independent() {
    let mut a = PssState::new(2, 1);
    a.begin();
    a.start_stream(1);
    let light = a.next_sample();
    a.start_stream(0);
    let cam = a.next_sample();
    assert_eq!(a.len(), 2);
    assert_eq!(a.raw_values(), &[cam, light]);
}

#[test]
fn small_step_moves_only_masked_streams() {
    let mut x = PssState::new(2, 5);
    x.get(3);
    x.materialize();
    let before = x.raw_values().to_vec();
    let mut y = x.clone();
    let m = SmallMutation::Gaussian { sigma: 0.01 };
    y.set_pending(
        Pending::Small {
            mutation: m,
            stream_mask: 0b01,
        },
        77,
    );
    y.materialize();
    assert_ne!(y.raw_values()[0], before[0]);
    assert_ne!(y.raw_values()[2], before[2]);
    assert_eq!(y.raw_values()[1], before[1]);
    assert_eq!(y.raw_values()[3], before[3]);
}

#[test]
fn large_step_resamples_everything() {
    let mut x = PssState::from_values(&[0.1, 0.2, 0.3]);
    x.set_pending(Pending::Large, 3);
    x.materialize();
    assert!(x
        .raw_values()
        .iter()
        .zip([0.1, 0.2, 0.3])
        .all(|(a, b)| *a != b));
}
