//! Disjoint sets of indices (union-find) in a slice of `u32` entries: the sleep stage's
//! islands (`sleep.rs`, by pool slot) and the solver's support marks (`support.rs`, by
//! solver body).
//!
//! Entry `i` holds the parent of `i`; a root holds itself. The root of a union is the
//! smaller of the two roots, so a parent is never larger than its child and a set's root
//! is its smallest index: the same sets and the same roots on every target. `find` halves
//! paths (each visited entry skips to its grandparent). Bit 31 of a root's entry
//! ([`MARK`]) marks its whole set, so the scratch stays one word per index; indices are
//! below `2³¹`. Integer work only, in the callers' order: deterministic.

/// Bit of a root's entry that marks its set.
const MARK: u32 = 1 << 31;

/// The parent bits of an entry.
const PARENT: u32 = !MARK;

/// Every index `0..entries.len()` a set of its own, unmarked.
pub(crate) fn reset(entries: &mut [u32]) {
    for (i, e) in entries.iter_mut().enumerate() {
        *e = i as u32;
    }
}

/// The parent of `i` (itself for a root, or for an index past the end).
#[inline]
fn parent(entries: &[u32], i: u32) -> u32 {
    entries.get(i as usize).map_or(i, |e| e & PARENT)
}

/// The root of `i`'s set, halving the path on the way. Each hop moves to a smaller
/// index: at most `entries.len()` hops.
pub(crate) fn find(entries: &mut [u32], mut i: u32) -> u32 {
    for _ in 0..=entries.len() {
        let p = parent(entries, i);
        if p == i {
            return i;
        }
        let grand = parent(entries, p);
        // `i` is not a root: its entry carries no mark.
        if let Some(e) = entries.get_mut(i as usize) {
            *e = grand;
        }
        i = grand;
    }
    i
}

/// Join the sets of `a` and `b`: the smaller root stays root and keeps the mark of
/// either.
pub(crate) fn union(entries: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(entries, a), find(entries, b));
    if ra == rb {
        return;
    }
    let (root, child) = if ra < rb { (ra, rb) } else { (rb, ra) };
    let entry = |i: u32| entries.get(i as usize).copied().unwrap_or(0);
    let mark = (entry(root) | entry(child)) & MARK;
    if let Some(e) = entries.get_mut(root as usize) {
        *e = root | mark;
    }
    if let Some(e) = entries.get_mut(child as usize) {
        *e = root;
    }
}

/// Mark the set of `i`.
pub(crate) fn mark(entries: &mut [u32], i: u32) {
    let r = find(entries, i);
    if let Some(e) = entries.get_mut(r as usize) {
        *e |= MARK;
    }
}

/// Point every entry straight at its root (roots keep their marks): afterwards
/// [`marked`] is one lookup. In index order, so each parent is flat before its children.
pub(crate) fn flatten(entries: &mut [u32]) {
    for i in 0..entries.len() {
        let r = find(entries, i as u32);
        if r != i as u32 {
            if let Some(e) = entries.get_mut(i) {
                *e = r;
            }
        }
    }
}

/// Whether `i`'s set is marked, once the entries are [`flatten`]ed (false past the end).
#[inline]
pub(crate) fn marked(entries: &[u32], i: u32) -> bool {
    let root = parent(entries, i);
    entries.get(root as usize).is_some_and(|e| e & MARK != 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn find_halves_paths_and_returns_the_root() {
        // A chain 4 → 3 → 2 → 1 → 0.
        let mut entries = [0u32, 0, 1, 2, 3];
        assert_eq!(find(&mut entries, 4), 0);
        // Halving: 4 now skips to 2, 2 to 0.
        assert_eq!(entries, [0, 0, 0, 2, 2]);
    }

    #[test]
    fn the_smaller_root_leads_and_marks_follow_unions_and_flattening() {
        let mut entries = [0u32; 6];
        reset(&mut entries);
        mark(&mut entries, 4);
        union(&mut entries, 5, 4);
        union(&mut entries, 4, 2);
        union(&mut entries, 1, 0);
        flatten(&mut entries);
        assert_eq!(entries, [0, 0, 2 | MARK, 3, 2, 2]);
        let marks: [bool; 6] = core::array::from_fn(|i| marked(&entries, i as u32));
        assert_eq!(marks, [false, false, true, false, true, true]);
        // Past the end: no set, no mark.
        assert!(!marked(&entries, 6));
    }

    /// Against a brute-force oracle: after random unions and marks, two indices share a
    /// root exactly when a chain of unions joins them, the root is the set's smallest
    /// index, and a set is marked exactly when one of its members was.
    #[test]
    fn sets_and_marks_match_a_brute_force_closure() {
        let mut rng = crate::rng::SplitMix64::new(11);
        for _ in 0..200 {
            let n = 1 + (rng.next_u64() % 40) as usize;
            let mut entries = [0u32; 40];
            let entries = &mut entries[..n];
            reset(entries);
            let mut label: [usize; 40] = core::array::from_fn(|i| i);
            let mut marked_by_hand = [false; 40];
            for _ in 0..(rng.next_u64() % 60) {
                let a = (rng.next_u64() % n as u64) as usize;
                let b = (rng.next_u64() % n as u64) as usize;
                if rng.next_u64().is_multiple_of(4) {
                    mark(entries, a as u32);
                    marked_by_hand[a] = true;
                } else {
                    union(entries, a as u32, b as u32);
                    let (from, to) = (label[a].max(label[b]), label[a].min(label[b]));
                    for l in label.iter_mut() {
                        if *l == from {
                            *l = to;
                        }
                    }
                }
            }
            flatten(entries);
            for i in 0..n {
                // Labels merge towards the smaller one: a set's label is its smallest index.
                assert_eq!(entries[i] & PARENT, label[i] as u32);
                let want = (0..n).any(|j| label[j] == label[i] && marked_by_hand[j]);
                assert_eq!(marked(entries, i as u32), want);
            }
        }
    }
}
