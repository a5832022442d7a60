//! Growing the disturbed region by what the step's chain reactions moved, a word of elements at a
//! time: the region takes every moved element and its neighbours (see [`super::Tissue::take_moved`],
//! the plain path, one element and one neighbour at a time through the lattice's adjacency).
//!
//! Most elements of a lattice have their neighbours at the same offsets in element order: on a
//! layer's grid, one along the row either way and one row either way, and the partner in the other
//! layer. The elements of each such pattern are a bit mask; the moved elements of a pattern, as
//! bits, shifted by each of its offsets are their neighbours, so a word of 64 elements grows in a
//! few operations. Elements of no common pattern (a grid's edges, a fibre missing) grow one by one
//! through the adjacency. Either way the region grows by the same set of elements, so the region
//! and every figure after it are the plain path's.
//!
//! A lift that raises the whole tent moves tens of thousands of elements in a step (the careful
//! exercise's final lift at 256 x 192: 25 000): the plain path took about 265 us of such a step on
//! the AVX2 machine, 10 ns a moved element.

use super::bits::Bits;
use crate::chainmail::Lattice;

/// Fewest elements a pattern of offsets has to be worth a mask (a 256th of the lattice). A sixteenth
/// until 2026-11-29 left out the fibre elements of the default scene at 512 x 384 (its fibre sites
/// every second element each way, half of them fibres: each layer's an eighth of it, a hair under a
/// sixteenth of the lattice once its edges are out), which then grew one by one: 2.7 % of the careful
/// exercise's CPU time there (perf, cpu-clock samples), 0.7 % after.
const PATTERN_SHARE: usize = 256;

/// Most distinct neighbours an element of a pattern has (a volume's grid has 6).
const KEY: usize = 8;

/// Most patterns kept (a two-layer grid has two: the upper layer's partners lie below, the lower's
/// above).
const PATTERNS: usize = 4;

/// One pattern: its neighbours' offsets in element order, each as whole words and the bits left
/// over (`off.div_euclid(64)`, `off.rem_euclid(64)`), and the elements that have exactly those
/// neighbours, as bits.
#[derive(Clone, Debug, Default)]
struct Pattern {
    shifts: Vec<(i64, u32)>,
    mask: Vec<u64>,
}

/// The lattice's common patterns, and scratch for one growth.
#[derive(Clone, Debug, Default)]
pub(crate) struct Growth {
    /// Elements of the lattice the patterns were found for (0: not yet).
    n: usize,
    patterns: Vec<Pattern>,
    /// Elements of no pattern, as bits.
    rest: Vec<u64>,
    /// The moved elements grown by their neighbours (scratch, all clear between growths).
    grown: Bits,
}

impl Growth {
    /// Finds the lattice's common patterns (when the tissue is built: a lattice never changes its
    /// adjacency; a growth before that finds them first).
    pub(crate) fn fit(&mut self, lat: &Lattice) {
        let n = lat.adj_start.len().saturating_sub(1);
        if self.n == n && n > 0 {
            return;
        }
        let words = n.div_ceil(64);
        // An element's neighbours' offsets, sorted, as a key of fixed size (`None`: more neighbours
        // than a key holds, which no common pattern has).
        let key = |e: usize| -> Option<(usize, [i64; KEY])> {
            let (s0, s1) = (lat.adj_start[e] as usize, lat.adj_start[e + 1] as usize);
            let nbrs = lat.adj_nbr.get(s0..s1).unwrap_or_default();
            let mut k = [0i64; KEY];
            let mut len = 0;
            for &m in nbrs {
                let o = m as i64 - e as i64;
                if k[..len].contains(&o) {
                    continue;
                }
                *k.get_mut(len)? = o;
                len += 1;
            }
            k[..len].sort_unstable();
            Some((len, k))
        };
        let mut counts: rustc_hash::FxHashMap<(usize, [i64; KEY]), usize> = Default::default();
        for e in 0..n {
            if let Some(k) = key(e) {
                *counts.entry(k).or_default() += 1;
            }
        }
        let mut common: Vec<((usize, [i64; KEY]), usize)> =
            counts.into_iter().filter(|(_, c)| *c * PATTERN_SHARE >= n).collect();
        // The most common first, ties by offsets: the same patterns whatever the map's order.
        common.sort_unstable_by(|a, b| b.1.cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
        common.truncate(PATTERNS);
        let keys: Vec<(usize, [i64; KEY])> = common.iter().map(|c| c.0).collect();
        self.patterns = keys
            .iter()
            .map(|&(len, k)| Pattern {
                shifts: k[..len].iter().map(|&o| (o.div_euclid(64), o.rem_euclid(64) as u32)).collect(),
                mask: vec![0; words],
            })
            .collect();
        self.rest = vec![0; words];
        for e in 0..n {
            let bit = 1u64 << (e % 64);
            let at = key(e).and_then(|k| keys.iter().position(|&c| c == k));
            match at.and_then(|i| self.patterns.get_mut(i)) {
                Some(p) => p.mask[e / 64] |= bit,
                None => self.rest[e / 64] |= bit,
            }
        }
        self.grown = Bits::new(n);
        self.n = n;
    }

    /// Takes the elements in `moved` (left empty) and calls `add` with each word of elements they and
    /// their neighbours make, as bits (word index, bits; every word with a bit once, in order). Bits
    /// of another length than the lattice's are left as they are (the region's ordering grows by
    /// them the plain way first). Costs the words with a bit, not the lattice's.
    pub(crate) fn take(&mut self, lat: &Lattice, moved: &mut Bits, add: impl FnMut(usize, u64)) {
        self.fit(lat);
        if moved.words() != self.grown.words() {
            return;
        }
        let (patterns, rest, grown) = (&self.patterns, &self.rest, &mut self.grown);
        moved.drain(|w, x| {
            grown.or(w, x);
            for p in patterns {
                let part = x & p.mask.get(w).copied().unwrap_or(0);
                if part == 0 {
                    continue;
                }
                for &(words_off, r) in &p.shifts {
                    // Bit `b` of `part` is element `64 w + b`; its neighbour at offset `off` is bit `b`
                    // of the word starting at element `64 w + off`, which spans two words: word
                    // `w + off.div_euclid(64)` from bit `r`, and the next.
                    let q = w as i64 + words_off;
                    if let Ok(q) = usize::try_from(q) {
                        grown.or(q, part << r);
                        if r != 0 {
                            grown.or(q + 1, part >> (64 - r));
                        }
                    } else if r != 0 && q == -1 {
                        // (Only the high part lands in the lattice: word 0.)
                        grown.or(0, part >> (64 - r));
                    }
                }
            }
            let mut odd = x & rest.get(w).copied().unwrap_or(0);
            while odd != 0 {
                let e = w * 64 + odd.trailing_zeros() as usize;
                odd &= odd - 1;
                let (Some(&s0), Some(&s1)) = (lat.adj_start.get(e), lat.adj_start.get(e + 1)) else {
                    continue;
                };
                for &m in lat.adj_nbr.get(s0 as usize..s1 as usize).unwrap_or_default() {
                    grown.set(m as usize);
                }
            }
        });
        grown.drain(add);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::Surface;
    use crate::tissue::{ConnectiveSpec, LayerSpec, LayeredSpec, Pinning, Tissue, TissueSpec};
    use proptest::prelude::*;

    fn tissue(nu: usize, nv: usize, density: f32) -> Tissue {
        tissue_spaced(nu, nv, density, 0.0)
    }

    /// [`tissue`] with the fibres' sites `spacing` apart (metres; 0: every element a site).
    fn tissue_spaced(nu: usize, nv: usize, density: f32, spacing: f32) -> Tissue {
        let layer = |name: &str, offset: f32| LayerSpec {
            name: name.into(),
            color: [1.0; 4],
            offset,
            material: crate::chainmail::Material::relative(1.15, 0.85, 0.3),
        };
        Tissue::build(&TissueSpec::Layered(LayeredSpec {
            surface: Surface::Plane { width: 0.06, depth: 0.05 },
            resolution: [nu, nv],
            u_coords: None,
            v_coords: None,
            layers: vec![layer("dura", 0.003), layer("arachnoid", 0.0)],
            connective: Some(ConnectiveSpec {
                material: crate::chainmail::Material::relative(2.0, 0.5, 0.5),
                density,
                min_gap: 0.0005,
                spacing,
            }),
            pinned: Pinning::Boundary,
        }))
        .expect("tissue")
    }

    /// The moved elements and their neighbours, one by one through the adjacency.
    fn plain(lat: &Lattice, moved: &[u32]) -> Vec<u32> {
        let mut set = std::collections::BTreeSet::new();
        for &e in moved {
            set.insert(e);
            let (s0, s1) = (lat.adj_start[e as usize] as usize, lat.adj_start[e as usize + 1] as usize);
            set.extend(lat.adj_nbr[s0..s1].iter().copied());
        }
        set.into_iter().collect()
    }

    /// Every element but a grid's edges has one of the common patterns, also where the fibres are an
    /// eighth of the elements (sites every second element each way, half of them fibres: the default
    /// scene at 512 x 384, whose fibre elements were a hair under a sixteenth of the lattice and so
    /// grew one by one through the adjacency).
    #[test]
    fn sparse_fibres_have_patterns_too() {
        let (nu, nv) = (64, 48);
        // Sites two element spacings apart (0.06 m over 63 spacings).
        let t = tissue_spaced(nu, nv, 0.5, 2.0 * 0.06 / 63.0);
        let lat = t.body().lattice();
        let fibres = (0..lat.adj_start.len() - 1)
            .filter(|&e| {
                let (s0, s1) = (lat.adj_start[e] as usize, lat.adj_start[e + 1] as usize);
                lat.adj_nbr[s0..s1].iter().any(|&m| (m as usize).abs_diff(e) == nu * nv)
            })
            .count();
        let n = 2 * nu * nv;
        assert!(fibres * 8 <= n + 4 * nu && fibres * 8 >= n - 4 * (nu + nv), "{fibres} fibre ends of {n}");
        let mut g = Growth::default();
        g.fit(lat);
        for e in 0..n {
            let (i, j) = (e % nu, (e / nu) % nv);
            let edge = i == 0 || i + 1 == nu || j == 0 || j + 1 == nv;
            assert!(edge || g.rest[e / 64] & (1 << (e % 64)) == 0, "element {e} ({i}, {j}) has no pattern");
        }
    }

    proptest! {
        /// Grown a word at a time, any set of moved elements (edges, corners, both layers, fibres
        /// missing) makes the set the adjacency makes, each word once and in order.
        #[test]
        fn a_word_at_a_time_grows_what_the_adjacency_grows(
            nu in 3usize..40,
            nv in 3usize..12,
            dense in any::<bool>(),
            picks in prop::collection::vec(any::<u32>(), 1..200),
        ) {
            let t = tissue(nu, nv, if dense { 1.0 } else { 0.6 });
            let lat = t.body().lattice();
            let n = t.body().element_count();
            let moved: Vec<u32> = picks.iter().map(|p| p % n as u32).collect();
            let mut bits = Bits::new(n);
            for &e in &moved {
                bits.set(e as usize);
            }
            let mut g = Growth::default();
            // Twice: the scratch is left clear for the next growth.
            for _ in 0..2 {
                let mut b = bits.clone();
                let mut got = Vec::new();
                let mut words = Vec::new();
                g.take(lat, &mut b, |w, x| {
                    words.push(w);
                    let mut x = x;
                    while x != 0 {
                        got.push((w * 64) as u32 + x.trailing_zeros());
                        x &= x - 1;
                    }
                });
                let mut left = 0;
                b.drain(|_, _| left += 1);
                prop_assert!(left == 0, "moved bits left");
                prop_assert!(words.windows(2).all(|p| p[0] < p[1]), "words out of order or twice");
                prop_assert_eq!(got, plain(lat, &moved));
            }
            // (A grid of a few elements a row has no pattern a sixteenth of its elements share.)
            prop_assert!(nu < 8 || nv < 8 || !g.patterns.is_empty(), "a grid with no common pattern");
        }
    }
}
