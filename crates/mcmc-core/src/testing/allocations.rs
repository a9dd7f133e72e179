//! A global allocator that counts allocations per thread: how a test shows that the steps of a
//! kernel allocate nothing once warmed up ("no allocation per mutation").

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

/// The system allocator, counting every allocation of the calling thread. Install it in a test
/// binary and compare [`CountingAllocator::allocations`] before and after the steps:
///
/// ```
/// use mcmc_core::testing::CountingAllocator;
///
/// #[global_allocator]
/// static ALLOCATOR: CountingAllocator = CountingAllocator;
///
/// fn main() {
///     let mut buffer: Vec<f64> = Vec::with_capacity(16);
///     let before = CountingAllocator::allocations();
///     buffer.extend([1.0, 2.0]); // within capacity: no allocation
///     assert_eq!(CountingAllocator::allocations(), before);
///     let copy = buffer.clone(); // a new vector: one allocation
///     assert_eq!(CountingAllocator::allocations(), before + 1);
///     assert_eq!(copy, buffer);
/// }
/// ```
///
/// Counts are per thread, so tests running beside each other do not disturb one another.
#[derive(Clone, Copy, Debug, Default)]
pub struct CountingAllocator;

impl CountingAllocator {
    /// Allocations made by the calling thread so far (reallocations count once each).
    #[must_use]
    pub fn allocations() -> usize {
        ALLOCATIONS.with(Cell::get)
    }
}

// SAFETY: every call is forwarded unchanged to the system allocator; counting touches only a
// thread-local `Cell` without a destructor, which never allocates.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|a| a.set(a.get() + 1));
        // SAFETY: the caller upholds `GlobalAlloc::alloc`'s contract, passed on unchanged.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System` through `alloc` with this `layout`.
        unsafe { System.dealloc(ptr, layout) }
    }
}
