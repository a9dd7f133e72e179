//! Alg. 1's per-region state for every region of a partition, in memory that costs nothing
//! until a region is first written.

use super::regional_scale::RegionStats;

/// One region's [`RegionStats`] encoded so that a fresh region ([`RegionStats::new`]) is all
/// zero bits: `[i, A, n XOR 1, visits since refinement, proposals, recent acceptance XOR
/// NaN]` (bit patterns; both XORs are exact round trips).
type Encoded = [u64; 6];

/// `f64::NAN`'s bits: a fresh region's recent acceptance.
const NAN_BITS: u64 = 0x7ff8_0000_0000_0000;

fn encode(r: &RegionStats) -> Encoded {
    [
        r.adapt.visits,
        r.adapt.accepted.to_bits(),
        r.adapt.updates ^ 1,
        r.visits_since_refine,
        r.proposals,
        r.recent_acceptance.to_bits() ^ NAN_BITS,
    ]
}

fn decode(e: &Encoded) -> RegionStats {
    let mut r = RegionStats::new();
    r.adapt.visits = e[0];
    r.adapt.accepted = f64::from_bits(e[1]);
    r.adapt.updates = e[2] ^ 1;
    r.visits_since_refine = e[3];
    r.proposals = e[4];
    r.recent_acceptance = f64::from_bits(e[5] ^ NAN_BITS);
    r
}

/// [`RegionStats`] of regions `0..len()`, every region fresh until first written, in one
/// zero-filled allocation: the pages of a partition with many regions of which few are
/// visited (the 4-D grid's 10^6) are mapped only where visited, and a visit costs one access,
/// as in a plain array.
#[derive(Clone, Debug, Default)]
pub(super) struct RegionTable {
    regions: Vec<Encoded>,
}

impl RegionTable {
    /// `regions` fresh regions.
    pub(super) fn new(regions: usize) -> Self {
        Self {
            regions: vec![[0; 6]; regions],
        }
    }

    /// Number of regions.
    pub(super) fn len(&self) -> usize {
        self.regions.len()
    }

    /// The state of region `k` (`None` if `k >= len()`).
    pub(super) fn get(&self, k: usize) -> Option<RegionStats> {
        self.regions.get(k).map(decode)
    }

    /// Reads the first and last word of every region in `regions` (ignoring ids `>= len()`), with
    /// nothing depending on one read before the next is issued: the cache misses of many
    /// scattered regions overlap instead of following one another. Changes nothing.
    pub(super) fn touch(&self, regions: impl Iterator<Item = usize>) {
        let mut any = 0u64;
        for k in regions {
            if let Some(e) = self.regions.get(k) {
                any ^= e[0] ^ e[5];
            }
        }
        std::hint::black_box(any);
    }

    /// Applies `f` to the state of region `k` (`None` if `k >= len()`).
    #[inline]
    pub(super) fn update<T>(
        &mut self,
        k: usize,
        f: impl FnOnce(&mut RegionStats) -> T,
    ) -> Option<T> {
        let e = self.regions.get_mut(k)?;
        let mut r = decode(e);
        let out = f(&mut r);
        *e = encode(&r);
        Some(out)
    }

    /// Sets the state of region `k`.
    ///
    /// # Panics
    /// If `k >= len()`.
    pub(super) fn set(&mut self, k: usize, stats: RegionStats) {
        self.regions[k] = encode(&stats);
    }

    /// Adds fresh regions up to `regions` in all (never shrinks).
    pub(super) fn grow(&mut self, regions: usize) {
        if regions > self.regions.len() {
            self.regions.resize(regions, [0; 6]);
        }
    }

    /// Restarts every region's visits since refinement at 0 (writing only regions that have
    /// some).
    pub(super) fn clear_refinement_visits(&mut self) {
        for e in &mut self.regions {
            if e[3] != 0 {
                e[3] = 0;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresh_regions_are_zero_and_states_round_trip() {
        assert_eq!(encode(&RegionStats::new()), [0; 6]);
        let mut t = RegionTable::new(1_000_000);
        assert_eq!(t.len(), 1_000_000);
        let fresh = t.get(999_999).unwrap();
        assert!(fresh.recent_acceptance.is_nan() && fresh.adapt == RegionStats::new().adapt);
        assert!(t.get(1_000_000).is_none());
        assert!(t.update(1_000_000, |_| ()).is_none());
        let mut r = RegionStats::new();
        r.adapt.visits = 3;
        r.adapt.accepted = 0.1 + 0.2;
        r.adapt.updates = 7;
        r.visits_since_refine = 11;
        r.proposals = 5;
        r.recent_acceptance = -0.0;
        t.set(7, r);
        let back = t.get(7).unwrap();
        assert_eq!(back.adapt, r.adapt);
        assert_eq!(back.recent_acceptance.to_bits(), (-0.0f64).to_bits());
        assert_eq!((back.visits_since_refine, back.proposals), (11, 5));
        assert_eq!(
            t.update(7, |s| {
                s.proposals += 1;
                s.proposals
            }),
            Some(6)
        );
        t.grow(1_000_002);
        assert_eq!(t.get(1_000_001).unwrap().adapt.updates, 1);
        t.clear_refinement_visits();
        assert_eq!(t.get(7).unwrap().visits_since_refine, 0);
        assert_eq!(t.get(7).unwrap().proposals, 6);
    }
}
