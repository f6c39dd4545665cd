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
//!   concurrently. It also keeps the bytes this thread holds and their
//!   peak ([`live_bytes`], [`peak_bytes`], [`reset_peak`]), for the tests
//!   that bound what reading an input may cost in memory:
//!
//!   ```ignore
//!   helicon_test_support::reset_peak();
//!   let before = helicon_test_support::live_bytes();
//!   // ... read the input ...
//!   assert!(helicon_test_support::peak_bytes() - before < 16 << 20);
//!   ```
//! - [`tmpdir`], a fresh scratch folder per test, removed when the test
//!   passes ([`Scratch`]); [`process_scratch`], one per test process,
//!   removed when it exits.
#![allow(unsafe_code)] // GlobalAlloc is an unsafe trait; Counting only forwards to System

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::{Path, PathBuf};

/// A global allocator that forwards to the system allocator and counts
/// each thread's allocations ([`allocations`]) and the bytes it holds
/// ([`live_bytes`], [`peak_bytes`]). Install it in a test binary with
/// `#[global_allocator]`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Counting;

thread_local! {
    static ALLOCS: Cell<usize> = const { Cell::new(0) };
    // bytes allocated minus bytes freed by this thread (memory freed by
    // another thread than the one that allocated it makes it drift; the
    // tests that read it allocate and free on one thread)
    static LIVE: Cell<isize> = const { Cell::new(0) };
    static PEAK: Cell<isize> = const { Cell::new(0) };
}

fn add_live(delta: isize) {
    // `try_with`: the thread's locals may be gone while it exits
    let _ = LIVE.try_with(|l| {
        let now = l.get().saturating_add(delta);
        l.set(now);
        let _ = PEAK.try_with(|p| p.set(p.get().max(now)));
    });
}

fn signed(n: usize) -> isize {
    isize::try_from(n).unwrap_or(isize::MAX)
}

// SAFETY: forwards every call unchanged to the system allocator and only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        add_live(signed(layout.size()));
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        add_live(-signed(layout.size()));
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
}

/// Heap allocations made by this thread so far (0 unless [`Counting`] is
/// the binary's global allocator). A reallocation counts as one.
pub fn allocations() -> usize {
    ALLOCS.with(Cell::get)
}

/// Heap bytes this thread has allocated and not freed (0 unless
/// [`Counting`] is the binary's global allocator).
pub fn live_bytes() -> isize {
    LIVE.with(Cell::get)
}

/// The most [`live_bytes`] has been since the thread started or since
/// [`reset_peak`].
pub fn peak_bytes() -> isize {
    PEAK.with(Cell::get)
}

/// Start a new peak at the current [`live_bytes`].
pub fn reset_peak() {
    PEAK.with(|p| p.set(live_bytes()));
}

/// A scratch folder for one test, removed with everything in it when the
/// value is dropped, so a test run leaves nothing behind in the system's
/// temporary folder. When the test fails (the thread is panicking), the
/// folder is kept and its path printed, for a look at what the test wrote.
///
/// It dereferences to a [`Path`], so `dir.join("log.csv")`, `&dir` where a
/// `&Path` is wanted and `dir.display()` work as on a path.
#[derive(Debug)]
pub struct Scratch {
    path: PathBuf,
}

impl Scratch {
    /// The folder's path, owned (for a struct that keeps it).
    #[must_use]
    pub fn to_path_buf(&self) -> PathBuf {
        self.path.clone()
    }
}

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<std::ffi::OsStr> for Scratch {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.path.as_os_str()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("scratch folder kept: {}", self.path.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}

/// A fresh scratch folder for one test: named after the test binary, the
/// process and `name` under the system's temporary folder, emptied if a
/// previous run left it, and removed when the returned [`Scratch`] is
/// dropped (kept when the test fails).
///
/// # Panics
/// When the folder cannot be created (a test helper: the test fails).
#[allow(clippy::expect_used)] // a test helper: a failure is the test's
pub fn tmpdir(name: &str) -> Scratch {
    let path = std::env::temp_dir().join(format!(
        "helicon_{}_{}_{name}",
        binary_name(),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&path);
    std::fs::create_dir_all(&path).expect("scratch folder");
    Scratch { path }
}

/// The folder of this test process's scratch files that are not one
/// test's own [`Scratch`] (output folders kept in an options struct, say):
/// `helicon_<binary>_<pid>` under the system's temporary folder, created on
/// first use and removed with everything in it when the process exits,
/// unless `HELICON_KEEP_SCRATCH` is set (to look at what a failed run
/// wrote).
///
/// # Panics
/// When the folder cannot be created (a test helper: the test fails).
#[allow(clippy::expect_used)] // a test helper: a failure is the test's
pub fn process_scratch() -> &'static Path {
    static ROOT: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    ROOT.get_or_init(|| {
        let path =
            std::env::temp_dir().join(format!("helicon_{}_{}", binary_name(), std::process::id()));
        let _ = std::fs::remove_dir_all(&path);
        std::fs::create_dir_all(&path).expect("scratch folder");
        extern "C" fn remove_at_exit() {
            if std::env::var_os("HELICON_KEEP_SCRATCH").is_none() {
                if let Some(root) = ROOT.get() {
                    let _ = std::fs::remove_dir_all(root);
                }
            }
        }
        unsafe extern "C" {
            fn atexit(callback: extern "C" fn()) -> std::ffi::c_int;
        }
        // SAFETY: `atexit` is the C library's; the callback is a plain
        // `extern "C" fn` that only removes a folder.
        let _ = unsafe { atexit(remove_at_exit) };
        path
    })
}

fn binary_name() -> String {
    std::env::current_exe()
        .ok()
        .and_then(|e| e.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .unwrap_or_else(|| "test".into())
}
