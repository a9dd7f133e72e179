//! Fixtures of the Langevin gradient tests: the bundled scenes they run on and the distance
//! between two gradients.

use std::path::Path;

use mcmc_core::Target;
use pss::PssState;
use render::mlt::PATH_STREAMS;
use render::scene::Scene;

/// The Cornell box and the bundled glossy-highlight, motion-blur and caustic-pool scenes at
/// `size` x `size`, named.
pub fn gradient_scenes(size: u32) -> Vec<(String, Scene)> {
    let mut v = vec![("cornell".to_owned(), Scene::cornell_box(size, size))];
    for name in ["glossy-highlight", "motion-blur", "caustic-pool"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../scenes")
            .join(format!("{name}.gltf"));
        let mut s = Scene::load(&path).expect("bundled scene");
        s.set_resolution(size, size);
        v.push((name.to_owned(), s));
    }
    v
}

/// `|a - b| / (|b| + 1)` in the Euclidean norm.
pub fn norm_relative_difference(a: &[f64], b: &[f64]) -> f64 {
    let d: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt();
    let n: f64 = b.iter().map(|y| y * y).sum::<f64>().sqrt();
    d / (n + 1.0)
}

/// The states of keys `0..20 000` (fresh [`PssState`]s of the path streams) at which `base`'s
/// value is finite, with their keys, evaluated once (so their read counts and tags are set).
pub fn finite_states<T>(base: &T) -> impl Iterator<Item = (u64, PssState)> + '_
where
    T: Target<State = PssState>,
    T::Payload: Default,
{
    let mut payload = T::Payload::default();
    (0..20_000u64).filter_map(move |key| {
        let mut x = PssState::new(PATH_STREAMS, key);
        base.evaluate(&mut x, &mut payload)
            .is_finite()
            .then_some((key, x))
    })
}
