//! Alg. 1's per-region state for every region of a partition, stored only for the regions
//! that were visited or made by a split.

use super::regional_scale::RegionStats;

/// [`RegionStats`] of regions `0..len()`, every region fresh ([`RegionStats::new`]) until
/// first written. A partition with many regions of which few are visited (the 4-D grid's
/// 10^6) then costs a zero-filled index (4 bytes a region, its pages mapped only where
/// visited) instead of a written array of full records, and the visited regions' records lie
/// together in the order of their first visit.
#[derive(Clone, Debug, Default)]
pub(super) struct RegionTable {
    /// Per region: 0 if fresh, else `1 +` its index in `stats`.
    slot: Vec<u32>,
    stats: Vec<RegionStats>,
}

impl RegionTable {
    /// `regions` fresh regions.
    pub(super) fn new(regions: usize) -> Self {
        Self {
            slot: vec![0; regions],
            stats: Vec::new(),
        }
    }

    /// Number of regions.
    pub(super) fn len(&self) -> usize {
        self.slot.len()
    }

    /// The state of region `k` (`None` if `k >= len()`).
    pub(super) fn get(&self, k: usize) -> Option<RegionStats> {
        let s = *self.slot.get(k)?;
        Some(if s == 0 {
            RegionStats::new()
        } else {
            self.stats[s as usize - 1]
        })
    }

    /// Mutable state of region `k`, stored from now on (`None` if `k >= len()`).
    pub(super) fn get_mut(&mut self, k: usize) -> Option<&mut RegionStats> {
        let slot = self.slot.get_mut(k)?;
        if *slot == 0 {
            self.stats.push(RegionStats::new());
            *slot = u32::try_from(self.stats.len()).expect("at most 2^32 - 1 stored regions");
        }
        Some(&mut self.stats[*slot as usize - 1])
    }

    /// Sets the state of region `k`.
    ///
    /// # Panics
    /// If `k >= len()`.
    pub(super) fn set(&mut self, k: usize, stats: RegionStats) {
        let len = self.len();
        *self
            .get_mut(k)
            .unwrap_or_else(|| panic!("region {k} of {len}")) = stats;
    }

    /// Adds fresh regions up to `regions` in all (never shrinks).
    pub(super) fn grow(&mut self, regions: usize) {
        if regions > self.slot.len() {
            self.slot.resize(regions, 0);
        }
    }

    /// The stored states (every region not among them is fresh).
    pub(super) fn stored_mut(&mut self) -> impl Iterator<Item = &mut RegionStats> {
        self.stats.iter_mut()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unwritten_regions_are_fresh_and_written_ones_kept() {
        let mut t = RegionTable::new(1_000_000);
        assert_eq!(t.len(), 1_000_000);
        assert_eq!(t.get(999_999).map(|r| r.proposals), Some(0));
        assert!(t.get(1_000_000).is_none());
        assert!(t.get_mut(1_000_000).is_none());
        t.get_mut(7).unwrap().proposals = 3;
        t.get_mut(5).unwrap().proposals = 2;
        t.get_mut(7).unwrap().proposals += 1;
        assert_eq!(t.get(7).unwrap().proposals, 4);
        assert_eq!(t.get(5).unwrap().proposals, 2);
        assert_eq!(t.stats.len(), 2, "only written regions are stored");
        let mut child = RegionStats::new();
        child.adapt.updates = 9;
        t.grow(1_000_002);
        t.set(1_000_001, child);
        assert_eq!(t.get(1_000_001).unwrap().adapt.updates, 9);
        let fresh = t.get(1_000_000).unwrap();
        assert!(fresh.recent_acceptance.is_nan() && fresh.adapt == RegionStats::new().adapt);
        for r in t.stored_mut() {
            r.visits_since_refine = 1;
        }
        assert_eq!(t.get(5).unwrap().visits_since_refine, 1);
        assert_eq!(t.get(6).unwrap().visits_since_refine, 0);
    }
}
