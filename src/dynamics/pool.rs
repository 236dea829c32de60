//! A fixed-capacity pool of slots addressed by generational handles.
//!
//! A new item takes the lowest free slot, so two worlds driven by the same calls in the
//! same order lay their bodies out identically. Removing an item bumps its slot's
//! generation, so an old handle to that slot is refused afterwards.

/// A handle to a body: slot index plus the slot's generation when the body was added.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BodyHandle {
    /// Slot index.
    pub index: u32,
    /// Generation of the slot.
    pub generation: u32,
}

/// `N` slots of `T`, each free or used, with a generation counter per slot.
#[derive(Clone, Debug)]
pub(crate) struct Pool<T: Copy, const N: usize> {
    slots: [Option<T>; N],
    generations: [u32; N],
    /// Number of used slots.
    len: u32,
    /// One past the highest used slot: loops stop there.
    high: u32,
}

impl<T: Copy, const N: usize> Pool<T, N> {
    /// An empty pool.
    pub const fn new() -> Self {
        Pool {
            slots: [None; N],
            generations: [0; N],
            len: 0,
            high: 0,
        }
    }

    /// Back to [`Pool::new`]'s state where it lies: every slot free, every generation 0
    /// (no copy of the pool on the stack).
    pub fn reset(&mut self) {
        self.slots.fill(None);
        self.generations.fill(0);
        self.len = 0;
        self.high = 0;
    }

    /// Number of used slots.
    #[inline]
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// One past the highest used slot index.
    #[inline]
    pub fn high(&self) -> usize {
        self.high as usize
    }

    /// Put `item` in the lowest free slot; `None` (and no change) when full.
    pub fn insert(&mut self, item: T) -> Option<BodyHandle> {
        let i = self.slots.iter().position(|s| s.is_none())?;
        let slot = self.slots.get_mut(i)?;
        *slot = Some(item);
        self.len += 1;
        self.high = self.high.max(i as u32 + 1);
        Some(BodyHandle {
            index: i as u32,
            generation: self.generations.get(i).copied().unwrap_or(0),
        })
    }

    /// Free the slot of `h`; returns the item, or `None` for a stale handle.
    pub fn remove(&mut self, h: BodyHandle) -> Option<T> {
        self.get(h)?;
        let i = h.index as usize;
        let item = self.slots.get_mut(i)?.take();
        if let Some(g) = self.generations.get_mut(i) {
            *g = g.wrapping_add(1);
        }
        self.len -= 1;
        while self.high > 0
            && self
                .slots
                .get(self.high as usize - 1)
                .is_some_and(|s| s.is_none())
        {
            self.high -= 1;
        }
        item
    }

    /// The item of a live handle.
    #[inline]
    pub fn get(&self, h: BodyHandle) -> Option<&T> {
        let i = h.index as usize;
        if self.generations.get(i).copied() != Some(h.generation) {
            return None;
        }
        self.slots.get(i)?.as_ref()
    }

    /// The item of a live handle, mutably.
    #[inline]
    pub fn get_mut(&mut self, h: BodyHandle) -> Option<&mut T> {
        let i = h.index as usize;
        if self.generations.get(i).copied() != Some(h.generation) {
            return None;
        }
        self.slots.get_mut(i)?.as_mut()
    }

    /// The item in slot `i`, if used.
    #[inline]
    pub fn at(&self, i: usize) -> Option<&T> {
        self.slots.get(i)?.as_ref()
    }

    /// The item in slot `i`, mutably, if used.
    #[inline]
    pub fn at_mut(&mut self, i: usize) -> Option<&mut T> {
        self.slots.get_mut(i)?.as_mut()
    }

    /// The handle of the item in slot `i`, if used.
    #[inline]
    pub fn handle_at(&self, i: usize) -> Option<BodyHandle> {
        self.at(i)?;
        Some(BodyHandle {
            index: i as u32,
            generation: self.generations.get(i).copied().unwrap_or(0),
        })
    }

    /// One past the highest slot that is used or has a non-zero generation: the slots a
    /// snapshot must carry so handles stay the same after a restore.
    pub fn touched(&self) -> usize {
        let mut n = self.high as usize;
        for (i, g) in self.generations.iter().enumerate().skip(n) {
            if *g != 0 {
                n = i + 1;
            }
        }
        n
    }

    /// Generation of slot `i` (0 when out of range).
    #[inline]
    pub fn generation(&self, i: usize) -> u32 {
        self.generations.get(i).copied().unwrap_or(0)
    }

    /// Overwrite slot `i` with a generation and an item (snapshot restore); keeps the
    /// counts right. Out-of-range slots are ignored.
    pub fn set_slot(&mut self, i: usize, generation: u32, item: Option<T>) {
        let (Some(slot), Some(g)) = (self.slots.get_mut(i), self.generations.get_mut(i)) else {
            return;
        };
        let was = slot.is_some();
        *slot = item;
        *g = generation;
        match (was, slot.is_some()) {
            (false, true) => self.len += 1,
            (true, false) => self.len -= 1,
            _ => {}
        }
        if item_present(self.slots.get(i)) {
            self.high = self.high.max(i as u32 + 1);
        } else {
            while self.high > 0 && !item_present(self.slots.get(self.high as usize - 1)) {
                self.high -= 1;
            }
        }
    }

    /// Two distinct used slots mutably at once; `None` if `i == j` or either is free.
    pub fn pair_mut(&mut self, i: usize, j: usize) -> Option<(&mut T, &mut T)> {
        if i == j || i >= N || j >= N {
            return None;
        }
        let (lo, hi, swapped) = if i < j { (i, j, false) } else { (j, i, true) };
        let (left, right) = self.slots.split_at_mut(hi);
        let a = left.get_mut(lo)?.as_mut()?;
        let b = right.first_mut()?.as_mut()?;
        Some(if swapped { (b, a) } else { (a, b) })
    }

    /// Iterate used slots in index order: `(index, &item)`.
    pub fn iter(&self) -> impl Iterator<Item = (usize, &T)> {
        let used = self.slots.get(..self.high as usize).unwrap_or(&[]);
        used.iter()
            .enumerate()
            .filter_map(|(i, s)| s.as_ref().map(|t| (i, t)))
    }

    /// Iterate used slots in index order, mutably.
    pub fn iter_mut(&mut self) -> impl Iterator<Item = (usize, &mut T)> {
        let used = self.slots.get_mut(..self.high as usize).unwrap_or(&mut []);
        used.iter_mut()
            .enumerate()
            .filter_map(|(i, s)| s.as_mut().map(|t| (i, t)))
    }
}

fn item_present<T>(slot: Option<&Option<T>>) -> bool {
    matches!(slot, Some(Some(_)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stale_handles_are_refused_and_lowest_slot_reused() {
        let mut p: Pool<u8, 3> = Pool::new();
        let a = p.insert(1).unwrap();
        let b = p.insert(2).unwrap();
        let c = p.insert(3).unwrap();
        assert!(p.insert(4).is_none());
        assert_eq!(p.remove(b), Some(2));
        assert_eq!(p.get(b), None);
        assert_eq!(p.remove(b), None);
        let d = p.insert(5).unwrap();
        assert_eq!(d.index, 1);
        assert_eq!(d.generation, 1);
        assert_eq!(p.get(d), Some(&5));
        assert_eq!(p.get(a), Some(&1));
        p.remove(c);
        assert_eq!(p.high(), 2);
        let (x, y) = p.pair_mut(1, 0).unwrap();
        assert_eq!((*x, *y), (5, 1));
    }
}
