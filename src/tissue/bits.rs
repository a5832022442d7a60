//! A bit per element, with a bit per word of them above it (which words may hold a bit), so that
//! taking the set bits back out in order costs the words that hold them, not the whole body.
//!
//! The disturbed region is put in element order every relaxing step (`settle.rs`), and the elements
//! a step's chain reactions moved join it by whole words (`grow.rs`). Both went over every word of
//! the body: 6 144 words at 512 x 384 two layers, where the region takes a few hundred (the careful
//! exercise's final lift: about 700). `hibitset` keeps such layers too, but only sets single bits;
//! the region grows by words.

/// A set of elements as bits, and a bit per word marking the words that may hold one. Every word
/// with a bit has its mark; a marked word may be empty (its bits taken some other way).
#[derive(Clone, Debug, Default)]
pub(crate) struct Bits {
    words: Vec<u64>,
    marks: Vec<u64>,
}

impl Bits {
    /// An empty set for `n` elements.
    pub(crate) fn new(n: usize) -> Self {
        let mut b = Self::default();
        b.fit(n);
        b
    }

    /// Sizes the set for `n` elements, empty, if it is sized for another count (else leaves it).
    pub(crate) fn fit(&mut self, n: usize) {
        let words = n.div_ceil(64);
        if self.words.len() != words {
            self.words = vec![0; words];
            self.marks = vec![0; words.div_ceil(64)];
        }
    }

    /// Words of bits (elements / 64, rounded up).
    pub(crate) fn words(&self) -> usize {
        self.words.len()
    }

    /// Adds element `e` (nothing past the last word).
    #[inline(always)]
    pub(crate) fn set(&mut self, e: usize) {
        self.or(e / 64, 1 << (e % 64));
    }

    /// Adds the bits `x` to word `w` (nothing if out of range).
    #[inline(always)]
    pub(crate) fn or(&mut self, w: usize, x: u64) {
        if x == 0 {
            return;
        }
        if let (Some(word), Some(mark)) = (self.words.get_mut(w), self.marks.get_mut(w / 64)) {
            *word |= x;
            *mark |= 1 << (w % 64);
        }
    }

    /// Takes every word with a bit out of the set, in order, calling `f` with its index and bits;
    /// the set is empty after.
    pub(crate) fn drain(&mut self, mut f: impl FnMut(usize, u64)) {
        let Self { words, marks } = self;
        for (m, mark) in marks.iter_mut().enumerate() {
            let mut x = std::mem::take(mark);
            while x != 0 {
                let w = m * 64 + x.trailing_zeros() as usize;
                x &= x - 1;
                if let Some(word) = words.get_mut(w) {
                    let bits = std::mem::take(word);
                    if bits != 0 {
                        f(w, bits);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_come_out_in_order_once() {
        let mut b = Bits::new(10_000);
        for e in [9_999, 3, 64, 65, 4_095, 4_096, 3] {
            b.set(e);
        }
        b.or(1, 1 << 5);
        b.set(10_048); // past the last word: nothing
        let mut out = Vec::new();
        b.drain(|w, x| {
            let mut x = x;
            while x != 0 {
                out.push(w * 64 + x.trailing_zeros() as usize);
                x &= x - 1;
            }
        });
        assert_eq!(out, vec![3, 64, 65, 69, 4_095, 4_096, 9_999]);
        let mut again = 0;
        b.drain(|_, _| again += 1);
        assert_eq!(again, 0);
    }
}
