//! Nothing allocates while it steps: the grid fast path (`grid_kernel`) and every
//! engine and integrator through `System::run` (`system_step`), counted by one
//! global allocator. Kept apart from the other test binaries: the allocator counts
//! every thread's allocations, so no unrelated test may run beside these.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard};
use std::time::Duration;

mod grid_kernel;
mod system_step;

struct Counting;

/// Allocations (and reallocations) so far, on every thread.
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator, only counting calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

static TURN: Mutex<()> = Mutex::new(());

/// The test's turn: the tests of this binary run one at a time (the harness starts
/// them on parallel threads, and the counter is global), whatever `--test-threads`
/// says. Held for the whole test. After taking it, a test waits 50 ms, so that the
/// harness's report of the test before (which allocates) is over before it counts.
fn one_at_a_time() -> MutexGuard<'static, ()> {
    // A test that failed holding the turn poisons it; the next may still run.
    let turn = TURN.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    std::thread::sleep(Duration::from_millis(50));
    turn
}
