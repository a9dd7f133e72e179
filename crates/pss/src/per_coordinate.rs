//! The per-coordinate layout stage: a 1-D kernel applied independently to every coordinate of
//! a fixed layout (the stages of the DRMLT authors' Tierney-Mira and Green-Mira).

use mcmc_core::{Proposal, Proposed};
use rand::{Rng, RngExt};

use crate::on_layout::{stored, LogQPair, OnLayout};
use crate::pairwise::Group;
use crate::state::PssState;
use crate::SmallMutation;

impl OnLayout<SmallMutation> {
    /// Calls `f` with every coordinate index of the layout in the streams of the mask, in
    /// the order of [`crate::PairLayout::groups`] (pairs flattened).
    fn for_each_index(&self, mut f: impl FnMut(usize)) {
        for group in self.layout.groups(self.stream_mask) {
            match group {
                Group::Pair(a, b) => {
                    f(a);
                    f(b);
                }
                Group::Single(a) => f(a),
            }
        }
    }
}

/// Every coordinate of the layout (in the streams of the mask) moved by one independent draw
/// of the 1-D kernel, wrapped onto `[0, 1)`; every other coordinate kept. This is the DR
/// paper's eq. 9 (Kelemen's perturbation "at each primary sample", section 4.3) and the
/// authors' Gaussian second stage (reference implementation, `transition.h`: one 1-D kernel
/// per dimension of the fixed-dimension state), on [`OnLayout`]'s materialised candidates
/// (the parent's values read through the candidate, so stale ones are caught up and logged).
///
/// The density is the product of the 1-D wrapped densities
/// ([`SmallMutation::log_density`]) over the layout's coordinates: symmetric, exact on states
/// materialised on the layout. Random numbers: per coordinate in order, Kelemen's two
/// (magnitude, sign) or the Gaussian's one.
impl Proposal<PssState> for OnLayout<SmallMutation> {
    fn propose<R: Rng + ?Sized>(&self, x: &PssState, y: &mut PssState, rng: &mut R) -> Proposed {
        self.begin_candidate(x, y, rng.random());
        if x.streams() != self.layout.streams() {
            return Proposed::Invalid { component: 0 };
        }
        let mutation = self.stage;
        self.for_each_index(|i| {
            let v = mutation.apply(y.get(i), 1, |_| rng.random());
            y.set(i, v);
        });
        Proposed::symmetric()
    }

    fn log_q(&self, from: &PssState, to: &PssState) -> f64 {
        if from.streams() != self.layout.streams() || to.streams() != self.layout.streams() {
            return f64::NEG_INFINITY;
        }
        let mut log_q = 0.0;
        self.for_each_index(|i| {
            log_q += self.stage.log_density(stored(from, i), stored(to, i));
        });
        if log_q.is_nan() {
            f64::NEG_INFINITY
        } else {
            log_q
        }
    }

    fn is_symmetric(&self) -> bool {
        true
    }
}

impl LogQPair for OnLayout<SmallMutation> {
    /// Per coordinate of the layout, skipping those where `a = x` and `b = y` bit for bit
    /// (the density is a product over coordinates).
    fn log_q_pair(&self, a: &PssState, b: &PssState, x: &PssState, y: &PssState) -> (f64, f64) {
        let streams = self.layout.streams();
        if [a, b, x, y].iter().any(|s| s.streams() != streams) {
            return (f64::NEG_INFINITY, f64::NEG_INFINITY);
        }
        let (mut forward, mut reverse) = (0.0, 0.0);
        self.for_each_index(|i| {
            let (va, vb, vx, vy) = (stored(a, i), stored(b, i), stored(x, i), stored(y, i));
            if va != vx || vb != vy {
                forward += self.stage.log_density(va, vb);
                reverse += self.stage.log_density(vx, vy);
            }
        });
        let clean = |v: f64| if v.is_nan() { f64::NEG_INFINITY } else { v };
        (clean(forward), clean(reverse))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{KelemenParams, PairLayout};
    use rand::SeedableRng;

    #[test]
    fn moves_every_layout_coordinate_and_keeps_the_rest() {
        let layout = PairLayout::new(2, &[3, 1]).unwrap();
        let stage = OnLayout::new(SmallMutation::Kelemen(KelemenParams::kelemen2002()), layout);
        let mut x = PssState::new(2, 7);
        for i in 0..8 {
            x.set(i, 0.1 * i as f64 + 0.05);
        }
        let mut y = PssState::new(2, 0);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(1);
        for _ in 0..200 {
            stage.propose(&x, &mut y, &mut rng);
            let (a, b) = (x.raw_values(), y.raw_values());
            // Layout: stream 0 at 0, 2, 4; stream 1 at 1. Others kept.
            for i in [0, 1, 2, 4] {
                let d = crate::pairwise::torus_displacement(a[i], b[i]).abs();
                assert!((1.0 / 1024.0..=1.0 / 64.0 + 1e-15).contains(&d), "{i}: {d}");
            }
            for i in [3, 5, 6, 7] {
                assert_eq!(a[i], b[i]);
            }
            let lq = stage.log_q(&x, &y);
            assert!(lq.is_finite());
            assert!((lq - stage.log_q(&y, &x)).abs() < 1e-9);
        }
        assert_eq!(stage.log_q(&x, &x), f64::NEG_INFINITY);
        let camera = stage.with_stream_mask(0b01);
        camera.propose(&x, &mut y, &mut rng);
        assert_eq!(x.raw_values()[1], y.raw_values()[1]);
        assert_ne!(x.raw_values()[0], y.raw_values()[0]);
    }
}
