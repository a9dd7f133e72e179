//! A chain's view of the gradient cache: a snapshot shared by all chains plus the entries this
//! chain added since the last round of the render loop.

use std::sync::Arc;

use super::cache::{GradientCache, Neighbours};

/// The gradient cache `C` as one chain sees it (Luan et al. 2020, section 6;
/// docs/methods/mala.md, "Sharing the cache among chains"): a *shared* snapshot (entries pooled from
/// all chains at the last round boundary of the render loop, read-only, behind an `Arc`)
/// plus a *local* cache of the entries this chain added since. Queries search both; the
/// capacity `H` counts both, so a chain alone fills its local cache to `H` and freezes.
///
/// Sharing is deterministic: [`CacheView::contribute`] appends the local entries to the
/// pooled cache in the order the render loop calls it (job order, then chain order) and
/// [`CacheView::receive`] installs the pooled cache as the new snapshot (see
/// [`super::CacheSharing`]). Between rounds a chain does not see other chains' new entries
/// (a staleness of at most one round), which is what keeps the image identical for any
/// thread count.
///
/// The dimension is fixed by the first entry or query (`None` before); points of another
/// dimension find no neighbours and are not stored.
#[derive(Clone, Debug)]
pub struct CacheView {
    shared: Arc<GradientCache>,
    local: GradientCache,
    capacity: usize,
    dim: Option<usize>,
}

/// The caches pooled over all chains of a render loop (the `Shared` value of
/// [`super::CacheSharing`]): one per dimension.
#[derive(Clone, Debug, Default)]
pub struct PooledCache {
    /// The pooled entries per dimension (absent until a chain contributed one of it).
    pub caches: std::collections::BTreeMap<usize, Arc<GradientCache>>,
    /// Rounds pooled so far.
    pub rounds: u64,
    /// Per dimension, the round after which its pooled cache was full (from then on the
    /// hybrid's chains of that dimension run frozen cache-driven MALA).
    pub full_after: std::collections::BTreeMap<usize, u64>,
}

impl PooledCache {
    /// Ends a round: counts it and records the dimensions whose caches became full.
    pub fn end_round(&mut self) {
        self.rounds += 1;
        for (&d, cache) in &self.caches {
            if cache.len() >= cache.capacity() {
                self.full_after.entry(d).or_insert(self.rounds);
            }
        }
    }

    /// One line on the caches: entries per dimension and when each became full.
    #[must_use]
    pub fn summary(&self) -> String {
        let parts: Vec<String> = self
            .caches
            .iter()
            .map(|(d, c)| match self.full_after.get(d) {
                Some(r) => format!("{d}-D full after round {r}"),
                None => format!("{d}-D {}/{}", c.len(), c.capacity()),
            })
            .collect();
        format!(
            "gradient caches after {} rounds: {}",
            self.rounds,
            if parts.is_empty() {
                "none".to_owned()
            } else {
                parts.join(", ")
            }
        )
    }
}

impl CacheView {
    /// An empty view of capacity `capacity` (`H`).
    #[must_use]
    pub fn new(capacity: usize) -> Self {
        Self {
            // Placeholders until the first point fixes the dimension.
            shared: Arc::new(GradientCache::new(1, capacity)),
            local: GradientCache::new(1, capacity),
            capacity,
            dim: None,
        }
    }

    fn ensure_dim(&mut self, d: usize) -> bool {
        match self.dim {
            Some(dim) => dim == d,
            None => {
                self.dim = Some(d);
                if self.shared.dim() != d {
                    self.shared = Arc::new(GradientCache::new(d, self.capacity));
                }
                self.local = GradientCache::new(d, self.capacity);
                true
            }
        }
    }

    /// Entries visible to this chain (shared + local).
    #[must_use]
    pub fn len(&self) -> usize {
        self.shared.len() + self.local.len()
    }

    /// True if no entry is visible.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The capacity `H`.
    #[must_use]
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// True once `H` entries are visible: caching has stopped (finite adaptation).
    #[must_use]
    pub fn is_full(&self) -> bool {
        self.len() >= self.capacity
    }

    /// The dimension of the cached points, once known.
    #[must_use]
    pub fn dim(&self) -> Option<usize> {
        self.dim
    }

    /// Adds `(point, gradient)` to the local cache unless the view is full or the dimension
    /// differs; returns whether it was stored.
    pub fn push(&mut self, point: &[f64], gradient: &[f64]) -> bool {
        if self.is_full() || !self.ensure_dim(point.len()) {
            return false;
        }
        self.local.push(point, gradient)
    }

    /// The `k` nearest entries within Euclidean distance `radius` of `v` (shared entries
    /// have source 0, local ones source 1), into `out`.
    pub fn query(&mut self, v: &[f64], radius: f64, k: usize, out: &mut Neighbours) {
        out.reset(k);
        if !self.ensure_dim(v.len()) {
            return;
        }
        self.shared.query(v, radius, 0, out);
        self.local.query(v, radius, 1, out);
    }

    /// The gradient of a neighbour returned by [`CacheView::query`].
    #[must_use]
    pub fn gradient(&self, source: u32, index: usize) -> &[f64] {
        if source == 0 {
            self.shared.gradient(index)
        } else {
            self.local.gradient(index)
        }
    }

    /// The point of a neighbour returned by [`CacheView::query`].
    #[must_use]
    pub fn point(&self, source: u32, index: usize) -> &[f64] {
        if source == 0 {
            self.shared.point(index)
        } else {
            self.local.point(index)
        }
    }

    /// Appends the local entries to the pooled cache of their dimension (until it holds `H`)
    /// and clears them.
    pub fn contribute(&mut self, pooled: &mut PooledCache) {
        if self.local.is_empty() {
            return;
        }
        let Some(d) = self.dim else { return };
        let cache = pooled
            .caches
            .entry(d)
            .or_insert_with(|| Arc::clone(&self.shared));
        Arc::make_mut(cache).extend_from(&self.local);
        self.local.clear();
    }

    /// Installs the pooled cache of this view's dimension as its shared snapshot (a view
    /// whose dimension is not fixed yet stays empty until it meets a point).
    pub fn receive(&mut self, pooled: &PooledCache) {
        if let Some(cache) = self.dim.and_then(|d| pooled.caches.get(&d)) {
            self.shared = Arc::clone(cache);
        }
    }
}
