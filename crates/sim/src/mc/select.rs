//! Exact percentiles of many value streams at once, in memory independent
//! of the number of values: radix selection in passes over data that can be
//! read again (the run store on disk).
//!
//! Each finite `f64` maps to a `u64` key whose unsigned order is
//! [`f64::total_cmp`]'s. Pass 1 counts the top `bits` bits of every key of
//! a stream; that gives the stream's size `n`, so the ranks of the order
//! statistics a type-7 percentile needs (`⌊h⌋` and `⌈h⌉`, `h = (n − 1) p`),
//! and the bucket each rank falls in. Each further pass counts the next
//! `bits` bits among the keys of that bucket only, until all 64 bits are
//! known: after `⌈64 / bits⌉` passes every order statistic is the exact
//! value the sorted data hold at that rank, so the percentiles are those of
//! [`percentile`](super::percentile) on the sorted values, bit for bit.
//! Memory: `streams × ranks × 2^bits` counters.

use super::McError;

/// The key of `x`: unsigned order = `total_cmp` order.
fn key(x: f64) -> u64 {
    let b = x.to_bits();
    if b >> 63 == 1 { !b } else { b | (1 << 63) }
}

/// The value of a key.
fn value(k: u64) -> f64 {
    f64::from_bits(if k >> 63 == 1 { k & !(1 << 63) } else { !k })
}

/// The type-7 interpolation between the order statistics `a ≤ b` at
/// fraction `f`; finite whenever they are (see [`percentile`](super::percentile)).
pub(super) fn interpolate(a: f64, b: f64, f: f64) -> f64 {
    let v = a + f * (b - a);
    // b − a overflows for values near ±f64::MAX: the convex form cannot; the
    // clamp undoes rounding past the two order statistics
    let v = if v.is_finite() {
        v
    } else {
        (1.0 - f) * a + f * b
    };
    v.max(a.min(b)).min(a.max(b))
}

/// One order statistic being narrowed down.
#[derive(Debug, Clone, Copy)]
struct Target {
    /// 0-based rank among the stream's values.
    rank: u64,
    /// Known top bits of its key.
    prefix: u64,
    /// How many top bits are known.
    known: u32,
    /// Rank within the keys sharing `prefix`.
    rest: u64,
}

/// Per stream, its percentiles (`None` when empty); and each stream's count.
pub(super) type Percentiles = (Vec<Vec<Option<f64>>>, Vec<u64>);

/// Values fed to [`percentiles`]: call `feed(stream, value)` for every
/// value of every stream, the same values in every pass.
pub(super) type Replay<'a> = dyn FnMut(&mut dyn FnMut(usize, f64)) -> Result<(), McError> + 'a;

/// Exact type-7 percentiles `ps` of each of `streams` streams (finite
/// values only; others are ignored), `None` for an empty stream, with
/// counters of `bits` bits (1 ≤ bits ≤ 16) per pass. Also returns each
/// stream's count. `replay` is called `⌈64 / bits⌉` times (once if every
/// stream is empty).
pub(super) fn percentiles(
    streams: usize,
    ps: &[f64],
    bits: u32,
    replay: &mut Replay<'_>,
) -> Result<Percentiles, McError> {
    let bits = bits.clamp(1, 16);
    let width = 1usize << bits;
    // pass 1: the top bits of every key
    let mut first = vec![0u64; streams * width];
    replay(&mut |s, x| {
        if s < streams && x.is_finite() {
            first[s * width + (key(x) >> (64 - bits)) as usize] += 1;
        }
    })?;
    let counts: Vec<u64> = first.chunks(width).map(|h| h.iter().sum()).collect();
    // per stream: its targets (distinct ranks) and, per p, (lo, hi, f)
    let mut targets: Vec<Vec<Target>> = vec![Vec::new(); streams];
    let mut plan: Vec<Vec<Option<(usize, usize, f64)>>> = vec![Vec::new(); streams];
    for s in 0..streams {
        let n = counts[s];
        for &p in ps {
            if n == 0 {
                plan[s].push(None);
                continue;
            }
            let h = (n - 1) as f64 * p.clamp(0.0, 1.0);
            let (lo, hi) = (h.floor() as u64, h.ceil() as u64);
            let mut at = |rank: u64| -> usize {
                if let Some(i) = targets[s].iter().position(|t| t.rank == rank) {
                    return i;
                }
                targets[s].push(Target {
                    rank,
                    prefix: 0,
                    known: 0,
                    rest: rank,
                });
                targets[s].len() - 1
            };
            let (a, b) = (at(lo), at(hi));
            plan[s].push(Some((a, b, h - lo as f64)));
        }
        let hist = &first[s * width..(s + 1) * width];
        for t in &mut targets[s] {
            narrow(t, hist, bits);
        }
    }
    drop(first);
    // further passes: the next bits within each target's bucket
    let max_targets = targets.iter().map(Vec::len).max().unwrap_or(0);
    let mut known = bits;
    while known < 64 && max_targets > 0 {
        let step = bits.min(64 - known);
        let w = 1usize << step;
        let mut hist = vec![0u64; streams * max_targets * w];
        {
            let targets = &targets;
            replay(&mut |s, x| {
                if s >= streams || !x.is_finite() {
                    return;
                }
                let k = key(x);
                for (i, t) in targets[s].iter().enumerate() {
                    if k >> (64 - t.known) == t.prefix {
                        let b = ((k >> (64 - t.known - step)) as usize) & (w - 1);
                        hist[(s * max_targets + i) * w + b] += 1;
                    }
                }
            })?;
        }
        for (s, ts) in targets.iter_mut().enumerate() {
            for (i, t) in ts.iter_mut().enumerate() {
                let o = (s * max_targets + i) * w;
                narrow(t, &hist[o..o + w], step);
            }
        }
        known += step;
    }
    let out = plan
        .iter()
        .zip(&targets)
        .map(|(pl, ts)| {
            pl.iter()
                .map(|e| {
                    e.map(|(a, b, f)| interpolate(value(ts[a].prefix), value(ts[b].prefix), f))
                })
                .collect()
        })
        .collect();
    Ok((out, counts))
}

/// Descend one level: the bucket of `hist` (counts of the next `step` bits
/// within `t`'s prefix) holding `t`'s rank.
fn narrow(t: &mut Target, hist: &[u64], step: u32) {
    let mut below = 0u64;
    let mut chosen = hist.len() - 1;
    for (b, &c) in hist.iter().enumerate() {
        if below + c > t.rest {
            chosen = b;
            break;
        }
        below += c;
    }
    t.rest -= below.min(t.rest);
    t.prefix = (t.prefix << step) | chosen as u64;
    t.known += step;
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::mc::percentile;

    /// splitmix64: a uniform in [0, 1).
    struct Uniform(u64);
    impl Uniform {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            (z ^ (z >> 31)) as f64 / 2f64.powi(64)
        }
    }

    fn exact(v: &[f64], ps: &[f64]) -> Vec<Option<f64>> {
        let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        s.sort_by(f64::total_cmp);
        ps.iter().map(|&p| percentile(&s, p)).collect()
    }

    #[test]
    fn keys_order_like_total_cmp_and_round_trip() {
        let xs = [
            f64::NEG_INFINITY,
            -f64::MAX,
            -1.5,
            -f64::MIN_POSITIVE,
            -0.0,
            0.0,
            5e-324,
            1.0,
            f64::MAX,
            f64::INFINITY,
        ];
        for w in xs.windows(2) {
            assert!(key(w[0]) < key(w[1]), "{w:?}");
        }
        for x in xs {
            assert_eq!(value(key(x)).to_bits(), x.to_bits());
        }
    }

    #[test]
    fn selection_equals_sorting_bit_for_bit() {
        let mut rng = Uniform(5);
        let ps = [0.05, 0.5, 0.95, 0.0, 1.0, 0.333];
        for n in [0usize, 1, 2, 3, 7, 100, 1001] {
            // three streams: spread values, many ties, a mix of signs and magnitudes
            let a: Vec<f64> = (0..n).map(|_| rng.next() * 10.0).collect();
            let b: Vec<f64> = (0..n).map(|_| (rng.next() * 3.0).floor()).collect();
            let c: Vec<f64> = (0..n)
                .map(|i| {
                    let x = rng.next() - 0.5;
                    if i % 5 == 0 {
                        x * 1e300
                    } else if i % 7 == 0 {
                        f64::NAN
                    } else {
                        x * 1e-300
                    }
                })
                .collect();
            let data = [a, b, c];
            for bits in [1, 5, 11, 16] {
                let mut passes = 0;
                let (got, counts) = percentiles(3, &ps, bits, &mut |feed| {
                    passes += 1;
                    for (s, v) in data.iter().enumerate() {
                        for &x in v {
                            feed(s, x);
                        }
                    }
                    Ok(())
                })
                .unwrap();
                for s in 0..3 {
                    let want = exact(&data[s], &ps);
                    let g: Vec<Option<u64>> = got[s].iter().map(|v| v.map(f64::to_bits)).collect();
                    let w: Vec<Option<u64>> = want.iter().map(|v| v.map(f64::to_bits)).collect();
                    assert_eq!(g, w, "n {n} bits {bits} stream {s}");
                    assert_eq!(
                        counts[s],
                        data[s].iter().filter(|x| x.is_finite()).count() as u64
                    );
                }
                assert!(
                    passes <= 64u32.div_ceil(bits),
                    "{passes} passes at {bits} bits"
                );
            }
        }
    }
}
