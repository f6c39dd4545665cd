//! # helicon-test-support
//!
//! What several test binaries of the workspace need and would otherwise
//! copy (a dev-dependency only; nothing here ships):
//!
//! - [`Counting`], a global allocator that counts this thread's heap
//!   allocations, for the tests that prove a hot path allocates nothing:
//!
//!   ```ignore
//!   #[global_allocator]
//!   static ALLOC: helicon_test_support::Counting = helicon_test_support::Counting;
//!   let before = helicon_test_support::allocations();
//!   // ... the hot path ...
//!   assert_eq!(helicon_test_support::allocations(), before);
//!   ```
//!
//!   Counts are per thread: the test harness's own threads allocate
//!   concurrently.
//! - [`tmpdir`], a fresh scratch folder per test.
#![allow(unsafe_code)] // GlobalAlloc is an unsafe trait; Counting only forwards to System

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::PathBuf;

/// A global allocator that forwards to the system allocator and counts
/// each thread's allocations ([`allocations`]). Install it in a test binary
/// with `#[global_allocator]`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Counting;

thread_local! {
    static ALLOCS: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: forwards every call unchanged to the system allocator and only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCS.with(|c| c.set(c.get() + 1));
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
}

/// Heap allocations made by this thread so far (0 unless [`Counting`] is
/// the binary's global allocator).
pub fn allocations() -> usize {
    ALLOCS.with(Cell::get)
}

/// A fresh scratch folder for one test: named after the test binary, the
/// process and `name` under the system's temporary folder, emptied if a
/// previous run left it.
///
/// # Panics
/// When the folder cannot be created (a test helper: the test fails).
#[allow(clippy::expect_used)] // a test helper: a failure is the test's
pub fn tmpdir(name: &str) -> PathBuf {
    let binary = std::env::current_exe()
        .ok()
        .and_then(|e| e.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .unwrap_or_else(|| "test".into());
    let d = std::env::temp_dir().join(format!("helicon_{binary}_{}_{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch folder");
    d
}
