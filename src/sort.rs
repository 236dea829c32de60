//! Sorting and reordering slices in place, without a panic path.
//!
//! `core`'s `sort_unstable`, `rotate_left`, `copy_within` and `copy_from_slice` carry
//! panic paths (an order-violation check, length asserts, bounds checks the optimiser
//! keeps), which the panic-never firmware check refuses. The sort here is a heapsort
//! (O(n log n) compares in every case, no allocation, no recursion, every access checked
//! by `get`), and pairs of `u32` take bucket passes first ([`sort_pairs`]). Neither is
//! stable, but both are deterministic: the output depends only on the input order and the
//! comparison, so equal keys land in the same order on every target. The pipeline sorts
//! unique keys, where stability does not matter. The solver's visit order, whose pairs
//! arrive in the order of their second components, takes a stable radix sort through a
//! scratch buffer instead ([`sort_pairs_radix`]): the same order, fewer instructions.

/// Sort `v` ascending.
pub(crate) fn sort_unstable<T: Ord>(v: &mut [T]) {
    sort_unstable_by(v, |a, b| a < b);
}

/// Sort pairs of `u32` ascending (as tuples compare: first, then second), comparing each
/// pair as one `u64` key.
///
/// Bucket passes, then a small sort per bucket: the keys' span `max − min` is cut into
/// ranges by its top significant bits (about one range per two pairs, at most
/// [`BUCKETS`]), each pair is moved into its range in place (a cycle walk: every swap
/// puts one pair where it belongs, at most `n` swaps), and each range is sorted by
/// insertion when it holds at most [`INSERTION_MAX`] pairs, by a second bucket pass over
/// its own span when it holds more, and by the heapsort past [`BUCKET_LEVELS`] passes
/// (so the worst case stays O(n log n)). The broad phase's and continuous collision's
/// slot pairs spread over the ranges, so most hold a few pairs. The result is the one
/// sorted order of the keys, whichever way it was reached.
pub(crate) fn sort_pairs(v: &mut [(u32, u32)]) {
    sort_keys_from(v, 0);
}

/// Sort `v` by its first components, keeping equal ones in the order they arrive: a
/// least-significant-digit radix sort, four passes of 8 bits, each a count and a move
/// through `buf` (a pass whose digit every key shares is skipped). About 80 instructions
/// a pair against [`sort_pairs`]' 150 to 300 on the solver's visit order. When `v` arrives
/// with its second components ascending (the solver's keys are pushed in contact order)
/// the result is [`sort_pairs`]'s: ties on the first component keep the second's order.
/// A `buf` shorter than `v` leaves the work to [`sort_pairs`].
///
/// Out of line: its four digit histograms (4 KiB) take stack only while it runs; inlined
/// into the step (as the compiler chose once the firmware's callers changed), they stayed
/// reserved under every later stage of it (a Cortex-M4F step 2.1 KB deeper).
#[inline(never)]
pub(crate) fn sort_pairs_radix(v: &mut [(u32, u32)], buf: &mut [(u32, u32)]) {
    let n = v.len();
    let Some(buf) = buf.get_mut(..n) else {
        sort_pairs(v);
        return;
    };
    // Every pass's digit counts, in one read of the keys.
    let mut starts = [[0u32; 256]; 4];
    for p in v.iter() {
        for (d, counts) in starts.iter_mut().enumerate() {
            if let Some(c) = counts.get_mut(digit(p.0, d)) {
                *c += 1;
            }
        }
    }
    let mut in_buf = false;
    for (d, counts) in starts.iter_mut().enumerate() {
        if counts.iter().any(|&c| c as usize == n) {
            continue;
        }
        // Counts to the first position of each digit's run.
        let mut at = 0u32;
        for c in counts.iter_mut() {
            let k = *c;
            *c = at;
            at = at.wrapping_add(k);
        }
        let (src, dst): (&[Pair], &mut [Pair]) = if in_buf {
            (&*buf, &mut *v)
        } else {
            (&*v, &mut *buf)
        };
        for p in src {
            if let Some(c) = counts.get_mut(digit(p.0, d)) {
                if let Some(slot) = dst.get_mut(*c as usize) {
                    *slot = *p;
                }
                *c += 1;
            }
        }
        in_buf = !in_buf;
    }
    if in_buf {
        copy_into(v, buf);
    }
}

/// A pair of [`sort_pairs_radix`].
type Pair = (u32, u32);

/// Byte `d` (0 the lowest) of `key`.
#[inline(always)]
fn digit(key: u32, d: usize) -> usize {
    ((key >> (8 * d as u32)) & 0xff) as usize
}

/// The key [`sort_pairs`] orders by.
#[inline]
fn pair_key(p: &(u32, u32)) -> u64 {
    (u64::from(p.0) << 32) | u64::from(p.1)
}

/// [`sort_pairs`] at bucket pass `level` (0 for the whole slice).
fn sort_keys_from(v: &mut [(u32, u32)], level: u32) {
    let less = |a: &(u32, u32), b: &(u32, u32)| pair_key(a) < pair_key(b);
    if v.len() <= INSERTION_MAX {
        insertion_sort_by(v, less);
        return;
    }
    // Past the levels, or too long for the `u32` positions: the heapsort.
    if level >= BUCKET_LEVELS || u32::try_from(v.len()).is_err() {
        sort_unstable_by(v, less);
        return;
    }
    let (mut lo, mut hi) = (u64::MAX, 0u64);
    for p in v.iter() {
        lo = lo.min(pair_key(p));
        hi = hi.max(pair_key(p));
    }
    // About one range per two keys, at most `BUCKETS`, and the shift that cuts the span
    // into that many.
    let bits = (usize::BITS - v.len().leading_zeros())
        .saturating_sub(1)
        .clamp(1, BUCKETS.trailing_zeros());
    let ranges = 1usize << bits;
    let span_bits = u64::BITS - (hi - lo).leading_zeros();
    let shift = span_bits.saturating_sub(bits);
    // `(k − lo) >> shift < ranges` for every key in [lo, hi]; `min` keeps it in range.
    let bucket = |p: &(u32, u32)| (((pair_key(p) - lo) >> shift) as usize).min(ranges - 1);
    let mut end = [0u32; BUCKETS];
    for p in v.iter() {
        if let Some(e) = end.get_mut(bucket(p)) {
            *e += 1;
        }
    }
    // Running sums: `end[b]` is where range `b` ends, `next[b]` its write position.
    let mut next = [0u32; BUCKETS];
    let mut at = 0u32;
    for (e, n) in end.iter_mut().zip(next.iter_mut()).take(ranges) {
        *n = at;
        at += *e;
        *e = at;
    }
    distribute(v, &mut next, &end, ranges, bucket);
    // Range `b` starts where range `b − 1` ends. A range of equal keys is sorted.
    let mut s = 0usize;
    for &e in end.iter().take(ranges) {
        let e = e as usize;
        let range = v.get_mut(s..e);
        s = e;
        if let (Some(range), true) = (range, shift > 0) {
            sort_keys_from(range, level + 1);
        }
    }
}

/// Bucket passes [`sort_pairs`] makes before the heapsort takes over (each pass keeps two
/// arrays of [`BUCKETS`] `u32` positions on the stack, 4 KiB).
const BUCKET_LEVELS: u32 = 2;

/// Ranges of [`sort_pairs`]' bucket pass (a power of two). Tuned when the solver's visit
/// order came here (one key per contact each step, about 7,000 in `jolt_pyramid`; now
/// [`sort_pairs_radix`]): 512 ranges left about 14 keys to each, sorted by insertion at
/// once. With 256 ranges and [`INSERTION_MAX`] 64 the sort took a third more
/// instructions (141 M against 106 M over 100 steps).
const BUCKETS: usize = 512;

/// Longest range [`sort_pairs`] sorts by insertion (at most `INSERTION_MAX²/2` moves, no
/// more than the heapsort's swaps and compares at this length; a random range of a few
/// dozen takes a quarter of that).
const INSERTION_MAX: usize = 32;

/// Move every element of `v` into its bucket's range: range `b < ranges` is
/// `[start_b, end[b])` with `next[b] = start_b` on entry. Each round either finds the element at a range's
/// write position already home (the position advances) or swaps it into its own range
/// (whose position advances): at most `2 n` rounds.
fn distribute<T>(
    v: &mut [T],
    next: &mut [u32; BUCKETS],
    end: &[u32; BUCKETS],
    ranges: usize,
    bucket: impl Fn(&T) -> usize,
) {
    let ranges = ranges.min(BUCKETS);
    let mut b = 0usize;
    for _ in 0..v.len().saturating_mul(2).saturating_add(BUCKETS) {
        // The first range with elements still to place, from `b` on.
        while b < ranges && next.get(b) >= end.get(b) {
            b += 1;
        }
        let (Some(&at), true) = (next.get(b), b < ranges) else {
            return;
        };
        let Some(home) = v.get(at as usize).map(&bucket) else {
            return;
        };
        let Some(to) = next.get_mut(home) else {
            return;
        };
        if home == b {
            *to += 1;
        } else {
            let dst = *to;
            *to += 1;
            swap(v, at as usize, dst as usize);
        }
    }
}

/// Sort a short `v` by insertion (stable, O(n²) compares: for short ranges only).
fn insertion_sort_by<T: Copy>(v: &mut [T], less: impl Fn(&T, &T) -> bool) {
    for i in 1..v.len() {
        let Some(&x) = v.get(i) else {
            return;
        };
        let mut j = i;
        while j > 0 {
            match v.get(j - 1) {
                Some(prev) if less(&x, prev) => {
                    let prev = *prev;
                    if let Some(slot) = v.get_mut(j) {
                        *slot = prev;
                    }
                    j -= 1;
                }
                _ => break,
            }
        }
        if let Some(slot) = v.get_mut(j) {
            *slot = x;
        }
    }
}

/// Sort `v` so that no element is `less` than the one before it. `less` must be a strict
/// weak order; if it is not, the result is some permutation of `v` (never a panic).
pub(crate) fn sort_unstable_by<T>(v: &mut [T], less: impl Fn(&T, &T) -> bool) {
    let n = v.len();
    // Build a max-heap: every parent at least as large as its children.
    let mut i = n / 2;
    while i > 0 {
        i -= 1;
        sift_down(v, i, n, &less);
    }
    // Move the largest to the end, one at a time.
    let mut end = n;
    while end > 1 {
        end -= 1;
        swap(v, 0, end);
        sift_down(v, 0, end, &less);
    }
}

/// Restore the heap order below `root` within `v[..end]`.
fn sift_down<T>(v: &mut [T], mut root: usize, end: usize, less: &impl Fn(&T, &T) -> bool) {
    // Each pass at least doubles `root`: at most `usize::BITS` passes.
    for _ in 0..usize::BITS {
        let left = root.saturating_mul(2).saturating_add(1);
        if left >= end {
            return;
        }
        let right = left + 1;
        let child = if right < end && is_less(v, left, right, less) {
            right
        } else {
            left
        };
        if !is_less(v, root, child, less) {
            return;
        }
        swap(v, root, child);
        root = child;
    }
}

/// `v[a] < v[b]`; false if either index is out of range.
fn is_less<T>(v: &[T], a: usize, b: usize, less: &impl Fn(&T, &T) -> bool) -> bool {
    match (v.get(a), v.get(b)) {
        (Some(x), Some(y)) => less(x, y),
        _ => false,
    }
}

/// Swap `v[a]` and `v[b]`; nothing if either index is out of range.
fn swap<T>(v: &mut [T], a: usize, b: usize) {
    if a < v.len() && b < v.len() {
        v.swap(a, b);
    }
}

/// Rotate `v` left by `k` places (`v[k]` comes first), by three reversals; `k` beyond
/// the length rotates by `k % len`.
pub(crate) fn rotate_left<T>(v: &mut [T], k: usize) {
    let n = v.len();
    if n == 0 {
        return;
    }
    let k = k % n;
    if let Some(head) = v.get_mut(..k) {
        head.reverse();
    }
    if let Some(tail) = v.get_mut(k..) {
        tail.reverse();
    }
    v.reverse();
}

/// Copy `src` into the front of `dst`, as far as both reach.
pub(crate) fn copy_into<T: Copy>(dst: &mut [T], src: &[T]) {
    for (d, s) in dst.iter_mut().zip(src) {
        *d = *s;
    }
}

/// Move `v[at..]` one place to the right (the last element falls off) and put `x` at
/// `at`; nothing if `at` is out of range. The sorted-insert step of small lists.
pub(crate) fn insert_shifting<T: Copy>(v: &mut [T], at: usize, x: T) {
    if at >= v.len() {
        return;
    }
    let mut i = v.len() - 1;
    while i > at {
        let prev = v.get(i - 1).copied();
        if let (Some(p), Some(slot)) = (prev, v.get_mut(i)) {
            *slot = p;
        }
        i -= 1;
    }
    if let Some(slot) = v.get_mut(at) {
        *slot = x;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// `sort` puts `v` in the order `core`'s sort gives.
    fn assert_sorts_like_core(
        mut v: std::vec::Vec<(u32, u32)>,
        sort: fn(&mut [(u32, u32)]),
        case: &str,
    ) {
        let mut want = v.clone();
        want.sort_unstable();
        sort(&mut v);
        assert_eq!(v, want, "{case}");
    }

    #[test]
    fn sorts_like_core_on_random_and_adversarial_inputs() {
        let mut rng = SplitMix64::new(7);
        for n in [0usize, 1, 2, 3, 7, 16, 100, 1000] {
            for pattern in 0..4 {
                let v: std::vec::Vec<(u32, u32)> = (0..n)
                    .map(|i| match pattern {
                        0 => ((rng.next_u64() % 50) as u32, i as u32),
                        1 => (i as u32, 0),
                        2 => ((n - i) as u32, 0),
                        _ => (7, i as u32),
                    })
                    .collect();
                assert_sorts_like_core(v, sort_unstable, &std::format!("n {n} pattern {pattern}"));
            }
        }
    }

    #[test]
    fn radix_sort_matches_sort_pairs_when_the_second_components_ascend() {
        let mut rng = SplitMix64::new(19);
        for n in [0usize, 1, 2, 3, 255, 256, 257, 1000, 9000] {
            for pattern in 0..6 {
                let mut v: std::vec::Vec<(u32, u32)> = (0..n)
                    .map(|i| {
                        let r = rng.next_u64();
                        let key = match pattern {
                            // The solver's keys: a class bit over a 31-bit hash.
                            0 => (r as u32 & 1) << 31 | (r >> 33) as u32,
                            // Many ties: stability decides their order.
                            1 => (r % 7) as u32,
                            // One key: every pass skipped.
                            2 => 0xdead_beef,
                            // Keys that differ in one byte only: three passes skipped.
                            3 => 0x1100_0033 | ((r as u32 & 0xff) << 8),
                            4 => u32::MAX - i as u32,
                            _ => r as u32,
                        };
                        // Ascending second components, with gaps.
                        (key, 3 * i as u32 + (r >> 62) as u32)
                    })
                    .collect();
                let mut want = v.clone();
                want.sort_unstable();
                let mut buf = std::vec![(7u32, 7u32); n + (n % 3)];
                sort_pairs_radix(&mut v, &mut buf);
                assert_eq!(v, want, "n {n} pattern {pattern}");
            }
        }
        // A short buffer: the bucket sort's answer, the same order.
        let mut v: std::vec::Vec<(u32, u32)> = (0..100u32)
            .map(|i| (i.wrapping_mul(2_654_435_761), i))
            .collect();
        let mut want = v.clone();
        want.sort_unstable();
        sort_pairs_radix(&mut v, &mut [(0, 0); 99]);
        assert_eq!(v, want, "short buffer");
    }

    #[test]
    fn sort_pairs_matches_core_on_random_skewed_and_duplicate_keys() {
        let mut rng = SplitMix64::new(11);
        for n in [
            0usize, 1, 2, 32, 33, 34, 64, 65, 100, 257, 513, 1000, 5000, 20000,
        ] {
            for pattern in 0..9 {
                let v: std::vec::Vec<(u32, u32)> = (0..n)
                    .map(|i| {
                        let r = rng.next_u64();
                        match pattern {
                            // The solver's keys: a class bit over a 31-bit hash.
                            0 => ((r as u32 & 1) << 31 | (r >> 33) as u32, i as u32),
                            // The broad phase's slot pairs.
                            1 => ((r % 300) as u32, (r >> 32) as u32 % 1000),
                            // One body in every pair: one range holds them all.
                            2 => (3, (r % 5000) as u32),
                            // Duplicates only.
                            3 => (9, 9),
                            // The whole key range, extremes included.
                            4 => match i % 3 {
                                0 => (u32::MAX, u32::MAX),
                                1 => (0, 0),
                                _ => (r as u32, (r >> 32) as u32),
                            },
                            // Skewed: most keys in one range, a few far away.
                            5 => {
                                if i % 50 == 0 {
                                    (u32::MAX - i as u32, 0)
                                } else {
                                    (0, (r % 40) as u32)
                                }
                            }
                            // Two dense clusters past the first two passes: the
                            // heapsort sorts them.
                            6 => {
                                if i % 50 == 0 {
                                    (u32::MAX - i as u32, 0)
                                } else {
                                    ((r % 2) as u32, (r >> 32) as u32)
                                }
                            }
                            7 => ((n - i) as u32, 0),
                            _ => (i as u32, (n - i) as u32),
                        }
                    })
                    .collect();
                assert_sorts_like_core(v, sort_pairs, &std::format!("n {n} pattern {pattern}"));
            }
        }
    }

    #[test]
    fn insertion_sort_matches_core() {
        let mut rng = SplitMix64::new(3);
        for n in 0..30usize {
            let mut v: std::vec::Vec<u64> = (0..n).map(|_| rng.next_u64() % 10).collect();
            let mut want = v.clone();
            want.sort_unstable();
            insertion_sort_by(&mut v, |a, b| a < b);
            assert_eq!(v, want, "n {n}");
        }
    }

    #[test]
    fn a_broken_order_permutes_and_does_not_panic() {
        let mut v: std::vec::Vec<u32> = (0..200).collect();
        // Not a strict weak order: "less" whenever the two differ.
        sort_unstable_by(&mut v, |a, b| a != b);
        let mut back = v.clone();
        back.sort_unstable();
        assert_eq!(back, (0..200).collect::<std::vec::Vec<u32>>());
    }

    #[test]
    fn rotate_left_matches_core() {
        for n in 0..9usize {
            for k in 0..12usize {
                let mut v: std::vec::Vec<usize> = (0..n).collect();
                let mut want = v.clone();
                if n > 0 {
                    want.rotate_left(k % n);
                }
                rotate_left(&mut v, k);
                assert_eq!(v, want, "n {n} k {k}");
            }
        }
    }

    #[test]
    fn insert_shifting_drops_the_last() {
        let mut v = [1, 2, 4, 5];
        insert_shifting(&mut v, 2, 3);
        assert_eq!(v, [1, 2, 3, 4]);
        insert_shifting(&mut v, 4, 9);
        assert_eq!(v, [1, 2, 3, 4]);
        insert_shifting(&mut v, 0, 0);
        assert_eq!(v, [0, 1, 2, 3]);
    }
}
