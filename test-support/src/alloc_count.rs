//! A global allocator that counts allocations (and reallocations), for tests and benches that
//! promise "no heap allocation per request". Install it in the test or bench binary:
//!
//! ```no_run
//! use drivemap_test_support::alloc_count::{self, Counting};
//!
//! #[global_allocator]
//! static GLOBAL: Counting = Counting;
//!
//! let before = alloc_count::this_thread();
//! let v = vec![1u8; 16];
//! assert_eq!(alloc_count::this_thread() - before, 1);
//! # drop(v);
//! ```
//!
//! `this_thread` counts what the calling thread allocated (tests run in parallel threads);
//! `all_threads` counts every thread (a bench whose server runs on another thread).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The counting allocator; forwards every call to [`System`].
pub struct Counting;

static ALL: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    static THIS: Cell<usize> = const { Cell::new(0) };
}

fn count() {
    ALL.fetch_add(1, Ordering::Relaxed);
    // During thread teardown the thread-local may be gone: then only the total counts.
    let _ = THIS.try_with(|c| c.set(c.get() + 1));
}

// SAFETY: the one `unsafe` of the test support. `GlobalAlloc` is an unsafe trait; every method
// forwards its arguments unchanged to the system allocator, which upholds the contract, and
// counting touches only an atomic and a `const`-initialised thread-local (no allocation, so no
// reentrancy).
#[allow(unsafe_code)]
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: forwarded unchanged (see above).
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: forwarded unchanged (see above).
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded unchanged (see above).
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        // SAFETY: forwarded unchanged (see above).
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// Allocations made by the calling thread so far.
pub fn this_thread() -> usize {
    THIS.with(Cell::get)
}

/// Allocations made by every thread so far.
pub fn all_threads() -> usize {
    ALL.load(Ordering::Relaxed)
}
