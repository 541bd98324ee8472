//! Sets of small ids with O(1) insert, remove and membership, a dense list of
//! the members, and a value kept beside each (per-frame cuts keep a copy of
//! each frontier node there, so that one pass over contiguous memory tests
//! them all).

/// Members `items[i]` with row `i` of `values` (a `Vec` of rows, or any
/// [`Columns`] that stores each field of a row in a column of its own).
#[derive(Debug, Clone)]
pub(crate) struct IdSet<C> {
    pub(crate) items: Vec<u32>,
    pub(crate) values: C,
    slot: Vec<u32>,
}

/// A table of rows that an [`IdSet`] keeps beside its ids.
pub(crate) trait Columns: Default {
    type Row;
    fn push(&mut self, row: Self::Row);
    fn swap_remove(&mut self, i: usize);
    fn clear(&mut self);
}

impl<T> Columns for Vec<T> {
    type Row = T;
    fn push(&mut self, row: T) {
        Vec::push(self, row);
    }
    fn swap_remove(&mut self, i: usize) {
        Vec::swap_remove(self, i);
    }
    fn clear(&mut self) {
        Vec::clear(self);
    }
}

const OUT: u32 = u32::MAX;

impl<C: Columns> IdSet<C> {
    /// An empty set of ids below `n`.
    pub(crate) fn new(n: usize) -> Self {
        IdSet {
            items: Vec::new(),
            values: C::default(),
            slot: vec![OUT; n],
        }
    }

    pub(crate) fn clear(&mut self) {
        for &i in &self.items {
            self.slot[i as usize] = OUT;
        }
        self.items.clear();
        self.values.clear();
    }

    pub(crate) fn len(&self) -> usize {
        self.items.len()
    }

    /// Adds `i` with `value()` unless it is in already.
    pub(crate) fn insert(&mut self, i: u32, value: impl FnOnce() -> C::Row) {
        if self.slot[i as usize] == OUT {
            self.slot[i as usize] = self.items.len() as u32;
            self.items.push(i);
            self.values.push(value());
        }
    }

    /// Takes `i` out if it is in; the last member moves to its place.
    pub(crate) fn remove(&mut self, i: u32) {
        let s = std::mem::replace(&mut self.slot[i as usize], OUT);
        if s == OUT {
            return;
        }
        self.items.swap_remove(s as usize);
        self.values.swap_remove(s as usize);
        if let Some(&moved) = self.items.get(s as usize) {
            self.slot[moved as usize] = s;
        }
    }

    /// Inserts (with `value()`) or removes `i`.
    pub(crate) fn set(&mut self, i: u32, member: bool, value: impl FnOnce() -> C::Row) {
        if member {
            self.insert(i, value);
        } else {
            self.remove(i);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The values follow their ids through inserts and swap-removes.
    #[test]
    fn values_stay_beside_their_ids() {
        let mut set: IdSet<Vec<u32>> = IdSet::new(10);
        for k in [3, 7, 1, 9, 3] {
            set.insert(k, || k * 10);
        }
        for k in [7, 5, 3] {
            set.remove(k);
        }
        set.set(0, true, || 0);
        set.set(9, false, || unreachable!());
        set.set(4, true, || 40);
        let mut ids = set.items.clone();
        ids.sort_unstable();
        assert_eq!(ids, [0, 1, 4]);
        assert_eq!(set.len(), 3);
        for (k, v) in set.items.iter().zip(&set.values) {
            assert_eq!(*v, k * 10);
            assert_eq!(
                set.slot[*k as usize] as usize,
                set.items.iter().position(|i| i == k).unwrap()
            );
        }
        assert_eq!(set.slot[7], OUT);
        set.clear();
        assert!(set.slot.iter().all(|s| *s == OUT) && set.len() == 0);
    }
}
