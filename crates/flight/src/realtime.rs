//! Real-time plumbing through safe wrappers: absolute-deadline sleeps on
//! `CLOCK_MONOTONIC` (`clock_nanosleep` with `TIMER_ABSTIME`, via `nix`),
//! SCHED_FIFO for a thread (`thread-priority`) and `mlockall` (`nix`). Each
//! privilege is tried; when the system refuses it the caller gets the
//! reason to warn with and runs without it.

use nix::sys::mman::{MlockAllFlags, mlockall};
use nix::sys::time::TimeSpec;
use nix::time::{ClockId, ClockNanosleepFlags, clock_gettime, clock_nanosleep};
use thread_priority::{
    RealtimeThreadSchedulePolicy, ThreadPriority, ThreadPriorityValue, ThreadSchedulePolicy,
    set_thread_priority_and_policy, thread_native_id,
};

/// Nanoseconds on `CLOCK_MONOTONIC` (0 if the clock cannot be read, which
/// Linux never does for this clock).
pub fn monotonic_ns() -> u64 {
    clock_gettime(ClockId::CLOCK_MONOTONIC)
        .map(|t| {
            u64::try_from(t.tv_sec()).unwrap_or(0) * 1_000_000_000
                + u64::try_from(t.tv_nsec()).unwrap_or(0)
        })
        .unwrap_or(0)
}

/// CPU time (user + system) of the whole process so far (s; 0 when the
/// system does not say).
pub fn process_cpu_s() -> f64 {
    use nix::sys::resource::{UsageWho, getrusage};
    getrusage(UsageWho::RUSAGE_SELF).map_or(0.0, |u| {
        let t = |tv: nix::sys::time::TimeVal| tv.tv_sec() as f64 + tv.tv_usec() as f64 * 1e-6;
        t(u.user_time()) + t(u.system_time())
    })
}

/// Sleep until the absolute `CLOCK_MONOTONIC` time `deadline_ns`
/// (`TIMER_ABSTIME`: no drift from the time spent computing). Interrupted
/// sleeps are resumed.
pub fn sleep_until_ns(deadline_ns: u64) {
    let secs = i64::try_from(deadline_ns / 1_000_000_000).unwrap_or(i64::MAX);
    let nanos = i64::try_from(deadline_ns % 1_000_000_000).unwrap_or(0);
    let ts = TimeSpec::new(secs, nanos);
    while let Err(nix::errno::Errno::EINTR) = clock_nanosleep(
        ClockId::CLOCK_MONOTONIC,
        ClockNanosleepFlags::TIMER_ABSTIME,
        &ts,
    ) {}
}

/// How long a lock-step wait polls before it blocks (SITL at full speed:
/// [`spin_for`]). The other side of a lock-step answers within tens of
/// microseconds; a wait that lasts longer (a loaded machine, the end of a
/// run) gives the CPU back and blocks.
pub const LOCKSTEP_SPIN: std::time::Duration = std::time::Duration::from_micros(300);

/// Lock-step waiting without a wake-up from sleep: calls `poll` (which
/// must not block) until it gives something or `spin` has passed,
/// yielding the CPU between calls (a runnable thread on this core, the
/// other side of the lock-step on a 2-core machine, runs first). `None`
/// when `spin` passed: the caller then blocks as it would have. Only for
/// lock-step runs: a real board's threads never spin.
pub fn spin_for<T>(spin: std::time::Duration, mut poll: impl FnMut() -> Option<T>) -> Option<T> {
    let until = monotonic_ns().saturating_add(u64::try_from(spin.as_nanos()).unwrap_or(u64::MAX));
    loop {
        if let Some(v) = poll() {
            return Some(v);
        }
        if monotonic_ns() >= until {
            return None;
        }
        std::thread::yield_now();
    }
}

/// Put the calling thread under SCHED_FIFO at `priority` (1..=99). `Err`
/// carries the system's reason (typically: not permitted without
/// CAP_SYS_NICE or an rtprio limit).
pub fn set_fifo(priority: u8) -> Result<(), String> {
    let value = ThreadPriorityValue::try_from(priority).map_err(|e| e.to_string())?;
    set_thread_priority_and_policy(
        thread_native_id(),
        ThreadPriority::Crossplatform(value),
        ThreadSchedulePolicy::Realtime(RealtimeThreadSchedulePolicy::Fifo),
    )
    .map_err(|e| format!("{e:?}"))
}

/// Lock the process's present and future memory (no page faults in the
/// control loop). `Err` carries the system's reason (typically: not
/// permitted, or RLIMIT_MEMLOCK too small).
pub fn lock_memory() -> Result<(), String> {
    mlockall(MlockAllFlags::MCL_CURRENT | MlockAllFlags::MCL_FUTURE).map_err(|e| e.to_string())
}

/// What the real-time setup achieved (written to `timing.json`).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct RealtimeStatus {
    /// The control task runs under SCHED_FIFO.
    pub sched_fifo: bool,
    /// Memory is locked.
    pub mlockall: bool,
    /// The warnings given (empty when everything asked for was granted).
    pub warnings: Vec<String>,
}

/// Fixed-size statistics of a time series in nanoseconds: a histogram of
/// 1 µs bins up to 100 ms (p50/p99 to 1 µs), the maximum exact.
#[derive(Debug, Clone)]
pub struct LatencyStats {
    bins: Box<[u32]>,
    count: u64,
    max_ns: u64,
    sum_ns: u128,
}

const BINS: usize = 100_000;

impl Default for LatencyStats {
    fn default() -> Self {
        Self::new()
    }
}

impl LatencyStats {
    /// Empty (allocates its bins once, here).
    pub fn new() -> Self {
        LatencyStats {
            bins: vec![0; BINS].into_boxed_slice(),
            count: 0,
            max_ns: 0,
            sum_ns: 0,
        }
    }

    /// Add one value (no allocation).
    pub fn push(&mut self, ns: u64) {
        let bin = usize::try_from(ns / 1000).unwrap_or(BINS - 1).min(BINS - 1);
        self.bins[bin] = self.bins[bin].saturating_add(1);
        self.count += 1;
        self.max_ns = self.max_ns.max(ns);
        self.sum_ns += u128::from(ns);
    }

    /// Values pushed.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// The q-quantile (0..=1) in µs, the upper edge of its 1 µs bin (0 when empty).
    pub fn quantile_us(&self, q: f64) -> f64 {
        if self.count == 0 {
            return 0.0;
        }
        let target = ((q.clamp(0.0, 1.0) * self.count as f64).ceil() as u64).max(1);
        let mut seen = 0u64;
        for (i, b) in self.bins.iter().enumerate() {
            seen += u64::from(*b);
            if seen >= target {
                return (i + 1) as f64;
            }
        }
        self.max_ns as f64 * 1e-3
    }

    /// The maximum (µs).
    pub fn max_us(&self) -> f64 {
        self.max_ns as f64 * 1e-3
    }

    /// The mean (µs).
    pub fn mean_us(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            self.sum_ns as f64 / self.count as f64 * 1e-3
        }
    }

    /// p50, p99, max, mean (µs) as a record for `timing.json`.
    pub fn summary(&self) -> LatencySummary {
        LatencySummary {
            count: self.count,
            p50_us: self.quantile_us(0.5),
            p99_us: self.quantile_us(0.99),
            max_us: self.max_us(),
            mean_us: self.mean_us(),
        }
    }
}

/// A latency distribution in `timing.json` (µs).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LatencySummary {
    /// Samples.
    pub count: u64,
    /// Median (µs, to the 1 µs bin).
    pub p50_us: f64,
    /// 99th percentile (µs, to the 1 µs bin).
    pub p99_us: f64,
    /// Maximum (µs, exact).
    pub max_us: f64,
    /// Mean (µs).
    pub mean_us: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_of_a_known_distribution() {
        let mut s = LatencyStats::new();
        for i in 0..1000u64 {
            s.push(i * 1000 + 500); // 0.5, 1.5, … 999.5 µs
        }
        assert_eq!(s.quantile_us(0.5), 500.0);
        assert_eq!(s.quantile_us(0.99), 990.0);
        assert_eq!(s.max_us(), 999.5);
        assert!((s.mean_us() - 500.0).abs() < 1e-9);
        s.push(10_000_000_000); // beyond the last bin: counted there, max exact
        assert_eq!(s.max_us(), 1e7);
    }

    #[test]
    fn absolute_sleep_does_not_return_early() {
        let t0 = monotonic_ns();
        sleep_until_ns(t0 + 2_000_000);
        assert!(monotonic_ns() >= t0 + 2_000_000);
    }
}
