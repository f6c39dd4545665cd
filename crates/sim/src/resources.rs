//! What the machine can hold: the memory budget long work checks itself
//! against before it starts (Monte Carlo campaigns, in-memory flight logs).

/// A `kB` figure of `/proc/meminfo`.
fn meminfo_kib(text: &str, key: &str) -> Option<u64> {
    text.lines()
        .find_map(|l| l.strip_prefix(key))
        .and_then(|r| r.trim().trim_end_matches("kB").trim().parse().ok())
}

/// The memory a campaign may use (bytes) and where the figure comes from:
/// half of what is available now, the lesser of the machine's
/// `MemAvailable` (`/proc/meminfo`) and the room left under a cgroup v2
/// limit (`memory.max − memory.current`); 1 GiB where neither can be read.
pub fn memory_budget() -> (u64, String) {
    let mut avail: Option<(u64, String)> = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| meminfo_kib(&t, "MemAvailable:"))
        .map(|k| {
            let b = k.saturating_mul(1024);
            (b, format!("{} MiB available on this machine", b >> 20))
        });
    let read_u64 = |p: &str| {
        std::fs::read_to_string(p)
            .ok()
            .and_then(|t| t.trim().parse::<u64>().ok())
    };
    if let (Some(max), Some(cur)) = (
        read_u64("/sys/fs/cgroup/memory.max"),
        read_u64("/sys/fs/cgroup/memory.current"),
    ) {
        let room = max.saturating_sub(cur);
        if avail.as_ref().is_none_or(|(a, _)| room < *a) {
            avail = Some((
                room,
                format!("{} MiB left under the cgroup limit", room >> 20),
            ));
        }
    }
    match avail {
        Some((b, why)) => (b / 2, format!("half of the {why}")),
        None => (
            1 << 30,
            "a default, the available memory being unreadable".into(),
        ),
    }
}
