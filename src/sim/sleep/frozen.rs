//! The frozen lists (the masked islands' kept contact points and forces) with
//! their bodies beside them in one compact array: the drop of the points of
//! trees that stop dozing (`Sleep::drop_unmasked_frozen`, most steps of a
//! dozing pile) tests each item's body there, eight to a cache line, not in
//! the item itself (one line or more an item, of a list nothing else reads
//! in the step).

use crate::contact::ContactPoint;
use crate::sim::ContactForce;

/// An item kept for a masked body.
pub(crate) trait OfBody: Copy {
    /// The body the item was kept for.
    fn body(&self) -> usize;
}

impl OfBody for ContactPoint {
    #[inline]
    fn body(&self) -> usize {
        self.body
    }
}

impl OfBody for ContactForce {
    #[inline]
    fn body(&self) -> usize {
        self.point.body
    }
}

/// A list of items in the order they were pushed, with each item's body at
/// the same index of `body` (`body[k] == items[k].body()`).
#[derive(Clone, Debug)]
pub(crate) struct Frozen<T> {
    items: Vec<T>,
    body: Vec<usize>,
}

impl<T> Default for Frozen<T> {
    fn default() -> Self {
        Self {
            items: Vec::new(),
            body: Vec::new(),
        }
    }
}

impl<T: OfBody> Frozen<T> {
    /// `item` appended.
    #[inline]
    pub fn push(&mut self, item: T) {
        self.body.push(item.body());
        self.items.push(item);
    }

    /// Every item dropped.
    pub fn clear(&mut self) {
        self.items.clear();
        self.body.clear();
    }

    /// The items whose body `keep` holds, in their order (what
    /// `Vec::retain(|x| keep(x.body()))` keeps), the test read from `body`:
    /// the items before the first one dropped are not touched.
    pub fn retain_bodies(&mut self, keep: impl Fn(usize) -> bool) {
        debug_assert_eq!(self.items.len(), self.body.len());
        let Some(first) = self.body.iter().position(|&b| !keep(b)) else {
            return;
        };
        let mut w = first;
        for r in first + 1..self.body.len().min(self.items.len()) {
            let b = self.body[r];
            if keep(b) {
                self.body[w] = b;
                self.items[w] = self.items[r];
                w += 1;
            }
        }
        self.body.truncate(w);
        self.items.truncate(w);
    }
}

impl<T> std::ops::Deref for Frozen<T> {
    type Target = [T];
    #[inline]
    fn deref(&self) -> &[T] {
        &self.items
    }
}

impl<'a, T> IntoIterator for &'a Frozen<T> {
    type Item = &'a T;
    type IntoIter = std::slice::Iter<'a, T>;
    fn into_iter(self) -> Self::IntoIter {
        self.items.iter()
    }
}
