//! The lattice: elements at rest positions and the links between them. Immutable once built: cutting
//! marks links broken in the [`Body`](super::Body), it does not change the lattice.

use super::coords::{norm, sub};
use super::error::{ChainMailError, finite};
use super::ids::{ElementId, LinkId};

/// Most elements a lattice may hold: 16 Mi elements, about 9 GiB of simulation state.
pub const MAX_ELEMENTS: usize = 1 << 24;
/// Approximate bytes of simulation state per element of a layered tissue, measured: the meninges at
/// 1024 × 512 in two layers (1 Mi elements) hold 607 MiB once built and 610 MiB after 20 steps
/// (2026-11-24). The body's positions, rest, links' ends, offsets, boxes and materials, adjacency and
/// slot rows, the workspace's scratch, a layer's normal pairs (partners, bounds, the links their paths
/// use: about 200) and the tissue's tear-scan table, link grids and region (the rest). Since
/// 2026-11-29 about 100 more: the settling's coarse-grid correction (its aggregates and scratch;
/// `dissect run` of the careful exercise at 512 × 384 peaked at 613 MB before it and 653 MB after).
pub const BYTES_PER_ELEMENT: usize = 700;

/// Bit set on an adjacency entry's link when the element owning the entry is the link's `b` end.
pub(crate) const SIDE_B: u32 = 1 << 31;

/// One of the three lattice axes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Axis {
    /// First axis (x, or u on a surface).
    X = 0,
    /// Second axis (y, or v on a surface).
    Y = 1,
    /// Third axis (z, or the normal offset h on a surface).
    Z = 2,
}

/// A rectilinear grid: rest coordinates along each axis, optionally wrapped.
#[derive(Clone, Debug, PartialEq)]
pub struct GridSpec {
    /// Rest coordinates along each axis, strictly increasing. Non-uniform spacing is allowed. A sheet
    /// has a single coordinate along the third axis.
    pub coords: [Vec<f32>; 3],
    /// For a wrapped axis, its period: the last element links back to the first with rest offset
    /// `period - (last - first)`. Used for the `u` axis of cylinders and spheres.
    pub wrap: [Option<f32>; 3],
    /// Per-axis reference length for the relative limits, as a factor of the link's rest length along
    /// its own axis. `[1, 1, 1]` for plain grids.
    pub scale: [f32; 3],
}

impl GridSpec {
    /// A uniform grid of `dims` elements with the given spacing, starting at the origin.
    pub fn uniform(dims: [usize; 3], spacing: f32) -> Self {
        let axis = |n: usize| (0..n).map(|i| i as f32 * spacing).collect::<Vec<_>>();
        Self { coords: [axis(dims[0]), axis(dims[1]), axis(dims[2])], wrap: [None; 3], scale: [1.0; 3] }
    }

    /// Number of elements along each axis.
    pub fn dims(&self) -> [usize; 3] {
        [self.coords[0].len(), self.coords[1].len(), self.coords[2].len()]
    }
}

/// A link as given to [`Lattice::from_links`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkSpec {
    /// First end.
    pub a: ElementId,
    /// Second end.
    pub b: ElementId,
    /// Rest offset from `a` to `b` in lattice coordinates. Differs from the difference of the rest
    /// positions only across a wrap seam.
    pub rest: [f32; 3],
    /// Reference length per axis for relative limits (the paper's `Dist`), usually the rest length on
    /// every axis.
    pub scale: [f32; 3],
}

/// Elements, links and their rest shape.
#[derive(Clone, Debug)]
pub struct Lattice {
    pub(crate) dims: Option<[usize; 3]>,
    pub(crate) rest: Vec<[f32; 3]>,
    /// Link ends `[a, b]`.
    pub(crate) ends: Vec<[u32; 2]>,
    /// Rest offset of each link, oriented so that its largest component is positive.
    pub(crate) rest_offset: Vec<[f32; 3]>,
    /// Axis of the largest rest component.
    pub(crate) axis: Vec<u8>,
    /// Reference lengths for relative limits.
    pub(crate) scale: Vec<[f32; 3]>,
    /// `rest_offset - (rest[b] - rest[a])`: non-zero only across wrap seams.
    pub(crate) jump: Vec<[f32; 3]>,
    /// Compressed adjacency: entries of element `i` are `adj_start[i]..adj_start[i + 1]`.
    pub(crate) adj_start: Vec<u32>,
    /// Neighbour of each adjacency entry.
    pub(crate) adj_nbr: Vec<u32>,
    /// Link of each adjacency entry, with [`SIDE_B`] set when the owner is the link's `b` end.
    pub(crate) adj_link: Vec<u32>,
    /// The two adjacency entries of each link (in `a`'s list, in `b`'s list).
    pub(crate) link_slots: Vec<[u32; 2]>,
}

fn check_count(count: u128) -> Result<usize, ChainMailError> {
    if count > MAX_ELEMENTS as u128 {
        return Err(ChainMailError::TooManyElements {
            count,
            limit: MAX_ELEMENTS,
            // (MiB first: the product overflows a 32-bit usize, as on wasm32.)
            limit_mib: MAX_ELEMENTS / (1 << 20) * BYTES_PER_ELEMENT,
        });
    }
    Ok(count as usize)
}

impl Lattice {
    /// A uniform sheet of `nx × ny` elements in the z = 0 plane.
    pub fn sheet(nx: usize, ny: usize, spacing: f32) -> Result<Self, ChainMailError> {
        Self::grid(&GridSpec::uniform([nx, ny, 1], spacing))
    }

    /// A uniform volume of `nx × ny × nz` elements.
    pub fn volume(nx: usize, ny: usize, nz: usize, spacing: f32) -> Result<Self, ChainMailError> {
        Self::grid(&GridSpec::uniform([nx, ny, nz], spacing))
    }

    /// A rectilinear grid, uniform or not, wrapped or not. Elements are numbered x fastest.
    pub fn grid(spec: &GridSpec) -> Result<Self, ChainMailError> {
        let dims = spec.dims();
        if dims.contains(&0) {
            return Err(ChainMailError::EmptyGrid { dims });
        }
        let n = check_count(dims.iter().fold(1u128, |a, &d| a.saturating_mul(d as u128)))?;
        for (axis, c) in spec.coords.iter().enumerate() {
            for &x in c {
                finite("grid coordinate", x)?;
            }
            if c.windows(2).any(|w| w[1] <= w[0]) {
                return Err(ChainMailError::BadCoordinates {
                    axis,
                    reason: "coordinates must be strictly increasing".into(),
                });
            }
            if let Some(p) = spec.wrap[axis] {
                finite("wrap period", p)?;
                let span = c[c.len() - 1] - c[0];
                if p <= span {
                    return Err(ChainMailError::BadCoordinates {
                        axis,
                        reason: format!("wrap period {p} must exceed the span {span} of the coordinates"),
                    });
                }
            }
        }
        for &s in &spec.scale {
            finite("grid scale", s)?;
        }
        let [nx, ny, nz] = dims;
        let mut rest = Vec::with_capacity(n);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    rest.push([spec.coords[0][i], spec.coords[1][j], spec.coords[2][k]]);
                }
            }
        }
        let index = |i: usize, j: usize, k: usize| (i + nx * (j + ny * k)) as u32;
        let mut links = Vec::new();
        for axis in 0..3 {
            let len = dims[axis];
            let wrap = spec.wrap[axis].filter(|_| len > 2);
            if len < 2 {
                continue;
            }
            for k in 0..nz {
                for j in 0..ny {
                    for i in 0..nx {
                        let at = [i, j, k];
                        let last = at[axis] + 1 == len;
                        if last && wrap.is_none() {
                            continue;
                        }
                        let mut to = at;
                        to[axis] = if last { 0 } else { at[axis] + 1 };
                        let c = &spec.coords[axis];
                        let d = if last {
                            wrap.unwrap_or(0.0) - (c[len - 1] - c[0])
                        } else {
                            c[at[axis] + 1] - c[at[axis]]
                        };
                        let mut off = [0.0; 3];
                        off[axis] = d;
                        links.push(LinkSpec {
                            a: ElementId(index(at[0], at[1], at[2])),
                            b: ElementId(index(to[0], to[1], to[2])),
                            rest: off,
                            scale: spec.scale.map(|s| s * d),
                        });
                    }
                }
            }
        }
        let mut lattice = Self::from_links(rest, &links)?;
        lattice.dims = Some(dims);
        Ok(lattice)
    }

    /// A curvilinear grid: topologically rectilinear, with any rest positions (x fastest). Each link's
    /// rest offset is the difference of its ends' rest positions.
    pub fn curvilinear(dims: [usize; 3], rest: Vec<[f32; 3]>) -> Result<Self, ChainMailError> {
        if dims.contains(&0) {
            return Err(ChainMailError::EmptyGrid { dims });
        }
        let n = check_count(dims.iter().fold(1u128, |a, &d| a.saturating_mul(d as u128)))?;
        if rest.len() != n {
            return Err(ChainMailError::BadCoordinates {
                axis: 0,
                reason: format!("{} rest positions for a {dims:?} grid of {n} elements", rest.len()),
            });
        }
        let [nx, ny, nz] = dims;
        let index = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
        let mut links = Vec::new();
        for axis in 0..3 {
            for k in 0..nz {
                for j in 0..ny {
                    for i in 0..nx {
                        let at = [i, j, k];
                        if at[axis] + 1 >= dims[axis] {
                            continue;
                        }
                        let mut to = at;
                        to[axis] += 1;
                        let (a, b) = (index(i, j, k), index(to[0], to[1], to[2]));
                        let off = sub(rest[b], rest[a]);
                        let len = norm(off);
                        links.push(LinkSpec {
                            a: ElementId(a as u32),
                            b: ElementId(b as u32),
                            rest: off,
                            scale: [len; 3],
                        });
                    }
                }
            }
        }
        let mut lattice = Self::from_links(rest, &links)?;
        lattice.dims = Some(dims);
        Ok(lattice)
    }

    /// Any topology: rest positions and an explicit list of links. This is the entry point for
    /// triangle and tetrahedral meshes.
    pub fn from_links(rest: Vec<[f32; 3]>, links: &[LinkSpec]) -> Result<Self, ChainMailError> {
        let n = check_count(rest.len() as u128)?;
        if n == 0 {
            return Err(ChainMailError::EmptyGrid { dims: [0, 0, 0] });
        }
        for p in &rest {
            for &x in p {
                finite("rest position", x)?;
            }
        }
        if links.len() >= (SIDE_B as usize) {
            return Err(ChainMailError::TooManyElements {
                count: links.len() as u128,
                limit: SIDE_B as usize,
                limit_mib: 0,
            });
        }
        let m = links.len();
        let mut ends = Vec::with_capacity(m);
        let mut rest_offset = Vec::with_capacity(m);
        let mut axis = Vec::with_capacity(m);
        let mut scale = Vec::with_capacity(m);
        let mut jump = Vec::with_capacity(m);
        let mut degree = vec![0u32; n + 1];
        for (index, l) in links.iter().enumerate() {
            let (a, b) = (l.a.index(), l.b.index());
            if a >= n || b >= n {
                return Err(ChainMailError::ElementOutOfRange { id: l.a.0.max(l.b.0), count: n });
            }
            if a == b {
                return Err(ChainMailError::DegenerateLink {
                    index,
                    reason: "both ends are the same element",
                });
            }
            for &x in l.rest.iter().chain(l.scale.iter()) {
                finite("link rest offset", x)?;
            }
            let k = (0..3).max_by(|&i, &j| l.rest[i].abs().total_cmp(&l.rest[j].abs())).unwrap_or(0);
            if l.rest[k] == 0.0 {
                return Err(ChainMailError::DegenerateLink { index, reason: "zero rest length" });
            }
            // Orient the link so that its rest offset points along +axis.
            let (a, b, off) = if l.rest[k] > 0.0 { (a, b, l.rest) } else { (b, a, l.rest.map(|x| -x)) };
            ends.push([a as u32, b as u32]);
            rest_offset.push(off);
            axis.push(k as u8);
            scale.push(l.scale.map(f32::abs));
            jump.push(sub(off, sub(rest[b], rest[a])));
            degree[a] += 1;
            degree[b] += 1;
        }
        let mut adj_start = Vec::with_capacity(n + 1);
        let mut acc = 0u32;
        for d in degree.iter().take(n) {
            adj_start.push(acc);
            acc += d;
        }
        adj_start.push(acc);
        let mut fill: Vec<u32> = adj_start[..n].to_vec();
        let mut adj_nbr = vec![0u32; acc as usize];
        let mut adj_link = vec![0u32; acc as usize];
        let mut link_slots = Vec::with_capacity(m);
        for (l, &[a, b]) in ends.iter().enumerate() {
            let sa = fill[a as usize];
            fill[a as usize] += 1;
            adj_nbr[sa as usize] = b;
            adj_link[sa as usize] = l as u32;
            let sb = fill[b as usize];
            fill[b as usize] += 1;
            adj_nbr[sb as usize] = a;
            adj_link[sb as usize] = l as u32 | SIDE_B;
            link_slots.push([sa, sb]);
        }
        Ok(Self {
            dims: None,
            rest,
            ends,
            rest_offset,
            axis,
            scale,
            jump,
            adj_start,
            adj_nbr,
            adj_link,
            link_slots,
        })
    }

    /// Number of elements.
    pub fn element_count(&self) -> usize {
        self.rest.len()
    }

    /// Number of links.
    pub fn link_count(&self) -> usize {
        self.ends.len()
    }

    /// Grid dimensions, for lattices built as grids.
    pub fn dims(&self) -> Option<[usize; 3]> {
        self.dims
    }

    /// The element at grid position `(i, j, k)`, for grid lattices.
    pub fn element_at(&self, i: usize, j: usize, k: usize) -> Option<ElementId> {
        let [nx, ny, nz] = self.dims?;
        (i < nx && j < ny && k < nz).then(|| ElementId((i + nx * (j + ny * k)) as u32))
    }

    /// Rest positions, lattice coordinates.
    pub fn rest_positions(&self) -> &[[f32; 3]] {
        &self.rest
    }

    /// The two ends of a link, oriented so that the rest offset from the first to the second points
    /// along the positive axis.
    pub fn link_ends(&self, link: LinkId) -> Option<[ElementId; 2]> {
        self.ends.get(link.index()).map(|&[a, b]| [ElementId(a), ElementId(b)])
    }

    /// The rest offset of a link (from its first end to its second).
    pub fn link_rest(&self, link: LinkId) -> Option<[f32; 3]> {
        self.rest_offset.get(link.index()).copied()
    }

    /// Axis along which a link runs (its largest rest component).
    pub fn link_axis(&self, link: LinkId) -> Option<usize> {
        self.axis.get(link.index()).map(|&a| a as usize)
    }

    /// The neighbours of an element with the links that join them.
    pub fn neighbours(&self, e: ElementId) -> impl Iterator<Item = (ElementId, LinkId)> + '_ {
        let i = e.index().min(self.rest.len());
        let (s, t) = if i < self.rest.len() {
            (self.adj_start[i] as usize, self.adj_start[i + 1] as usize)
        } else {
            (0, 0)
        };
        (s..t).map(|k| (ElementId(self.adj_nbr[k]), LinkId(self.adj_link[k] & !SIDE_B)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sheet_has_expected_links() {
        let l = Lattice::sheet(4, 3, 1.0).expect("sheet");
        assert_eq!(l.element_count(), 12);
        assert_eq!(l.link_count(), 3 * 3 + 4 * 2);
    }

    #[test]
    fn wrapped_axis_links_last_to_first() {
        let mut spec = GridSpec::uniform([4, 2, 1], 1.0);
        spec.wrap[0] = Some(4.0);
        let l = Lattice::grid(&spec).expect("grid");
        assert_eq!(l.link_count(), 4 * 2 + 4);
        let seam = (0..l.link_count())
            .map(|i| LinkId(i as u32))
            .find(|&id| l.link_ends(id) == Some([ElementId(3), ElementId(0)]))
            .expect("seam link");
        assert_eq!(l.link_rest(seam), Some([1.0, 0.0, 0.0]));
        assert_eq!(l.jump[seam.index()], [4.0, 0.0, 0.0]);
    }

    #[test]
    fn empty_and_huge_grids_are_refused() {
        assert!(matches!(Lattice::sheet(0, 3, 1.0), Err(ChainMailError::EmptyGrid { .. })));
        let huge = GridSpec { coords: [vec![], vec![], vec![]], wrap: [None; 3], scale: [1.0; 3] };
        assert!(Lattice::grid(&huge).is_err());
        assert!(matches!(
            Lattice::grid(&GridSpec::uniform([100_000, 100_000, 1], 1.0)),
            Err(ChainMailError::TooManyElements { .. })
        ));
    }
}
