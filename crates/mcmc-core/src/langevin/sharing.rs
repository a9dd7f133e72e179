//! Sharing one gradient cache among the chains of a render loop, deterministically.

use super::cache_view::PooledCache;
use super::kernel::HasGradientCache;
use crate::controller::{Controller, SharedController};
use crate::kernel::StepInfo;

/// The controller that shares the gradient cache of cache-driven and hybrid MALA among all
/// chains of a render loop (`render_loop::RenderLoop`, feature `parallel`): at every round boundary each chain's new
/// entries are appended to the pooled cache in job order and chain order (until it holds
/// `H`), and every chain receives the pooled cache as its new shared snapshot. Within a round a
/// chain sees the snapshot plus its own new entries; so the image is identical for any
/// thread count under a mutation budget (the paper's implementation shares one cache behind a
/// lock instead, which is not reproducible).
///
/// It adapts nothing per step (the adaptation lives in the kernel's
/// [`super::Adaptation`]); [`Controller::is_frozen`] is always true.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CacheSharing;

impl<K: ?Sized, S> Controller<K, S> for CacheSharing {
    fn after_step(&mut self, _kernel: &mut K, _info: &StepInfo) {}
    fn is_frozen(&self) -> bool {
        true
    }
}

impl<K: HasGradientCache + ?Sized> SharedController<K> for CacheSharing {
    type Shared = PooledCache;
    fn contribute(&mut self, kernel: &mut K, pooled: &mut PooledCache) {
        kernel.for_each_gradient_cache(&mut |view| view.contribute(pooled));
    }
    fn receive(&mut self, kernel: &mut K, pooled: &PooledCache) {
        kernel.for_each_gradient_cache(&mut |view| view.receive(pooled));
    }
    fn end_round(pooled: &mut PooledCache) {
        pooled.end_round();
    }
    fn summary(pooled: &PooledCache) -> Option<String> {
        (!pooled.caches.is_empty()).then(|| pooled.summary())
    }
}
