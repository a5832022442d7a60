//! Elastic cells: the relaxation of a volume whose material has a Poisson's ratio
//! ([`crate::chainmail::Material::poisson_ratio`]).
//!
//! Gibson's relaxation lowers the energy of the links, each a spring on its offset: a graph Laplacian,
//! which moves each coordinate on its own, so a pressed block neither bulges nor resists a change of
//! volume. With a Poisson's ratio the energy is instead linear elasticity over the lattice's cells:
//! each cell of eight elements (every one of its twelve edges intact, its material the one of its
//! first edge along x) is cut into six tetrahedra around its main diagonal (Kuhn's split, as
//! `fem::TetMesh::block` cuts the FEM reference's cubes) and carries `½ uᵀ K u`, `K` the tetrahedra's
//! summed stiffness for the material's Young's modulus times its `stiffness` (the weight of a material
//! in relaxation, 1 by default). In a volume, whose lattice coordinates are metres, `K u` is the force
//! in newtons that holds each element where it is ([`Body::elastic_force`]).
//!
//! An element's update is a projected Gauss-Seidel step, coordinate by coordinate: each coordinate
//! goes to the minimum of the energy along it, with the other coordinates and every other element
//! held, then into the element's link boxes as the plain kernel clamps (never further out than it
//! already is, never backwards). Each coordinate's move lowers the energy or leaves it, so the sweeps
//! converge to the elastic energy's minimum within the links' limits where the limits allow it: with
//! limits that do not bind, the linear FEM's answer on the same grid (`fem::compare` measures it).
//! Elements in no elastic cell (a volume's material without a ratio, or cells cut open around them)
//! relax as before.
//!
//! Cells are found again whenever a link breaks or a material changes, at the start of a sweep; each
//! cell stiffness and stencil is computed once per body.

use rustc_hash::FxHashMap;

use crate::chainmail::body::{Body, FIXED, INTACT};
use crate::chainmail::coords::clamp;
use crate::chainmail::ids::ElementId;
use crate::chainmail::relax::kernel::FLUSH;

/// No elastic energy in this cell.
const NONE: u32 = u32::MAX;

/// Kuhn's six tetrahedra of a cube, as corner numbers (bit 0: +x, bit 1: +y, bit 2: +z), the FEM's
/// split.
const KUHN: [[usize; 4]; 6] =
    [[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7]];

/// One cell stiffness: the 3 × 3 block `K[a][b]` coupling corner `a`'s force to corner `b`'s
/// displacement, row-major, at `a * 8 + b`.
pub(crate) type CellStiffness = [[f32; 9]; 64];

/// The elastic cells of a body (empty when it has none).
#[derive(Clone, Debug, Default)]
pub(crate) struct Elastic {
    /// Grid nodes along x, y, z (each at least 2), or zero when the body has no cells.
    dims: [usize; 3],
    /// The body's boxes epoch and broken links these cells were found at (the cells depend on the
    /// links' materials and which links are intact, not on pins and holds).
    found_at: Option<(u64, u64)>,
    /// Whether any cell is elastic.
    any: bool,
    /// For each cell (x fastest, `(nx − 1)(ny − 1)(nz − 1)`), its stiffness in `stiffness`, or
    /// [`NONE`].
    cell: Vec<u32>,
    /// The distinct cell stiffnesses.
    stiffness: Vec<CellStiffness>,
    /// The distinct stencils (see [`Stencil`]).
    stencil: Vec<Stencil>,
    /// Where each stencil sits, by the stiffness of the element's eight cells.
    stencil_index: FxHashMap<[u32; 8], u32>,
    /// For each element, its stencil, or [`NONE`] where it lies in no elastic cell.
    element: Vec<u32>,
    /// Where each stiffness sits, by Poisson's ratio, modulus and cell sides.
    index: FxHashMap<[u32; 5], u32>,
}

/// What an element's elastic update reads: its cells' stiffness assembled into a 27-point stencil.
/// Elements whose eight cells are alike (the interior of a block, each face, edge and corner, the
/// elements beside a cut) share one.
#[derive(Clone, Debug)]
pub(crate) struct Stencil {
    /// The diagonal block: the element's force from its own displacement.
    diag: [f32; 9],
    /// The neighbours' blocks (each coupling the element's force to a neighbour's displacement), with
    /// their element offsets from the element in a grid of the body's dims; zero blocks left out.
    entries: Vec<(isize, [f32; 9])>,
}

/// The stiffness of a box cell of sides `side` for Young's modulus `scale` and Poisson's ratio `nu`,
/// summed over Kuhn's tetrahedra: for a tetrahedron of volume `V` and shape-function gradients `g`,
/// `K[a][b]_ij = V (λ g_a,i g_b,j + μ g_a,j g_b,i + μ (g_a · g_b) δ_ij)`.
pub(crate) fn cell_stiffness(side: [f64; 3], nu: f64, scale: f64) -> CellStiffness {
    let lambda = scale * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mu = scale / (2.0 * (1.0 + nu));
    let corner = |c: usize| [0, 1, 2].map(|k| if (c >> k) & 1 == 1 { side[k] } else { 0.0 });
    let mut k = [[0.0f64; 9]; 64];
    for tet in KUHN {
        let p = tet.map(corner);
        let e = [1, 2, 3].map(|a| [0, 1, 2].map(|i| p[a][i] - p[0][i]));
        // Rows of the inverse of the matrix whose columns are `e`: the gradients of N1..N3.
        let det = e[0][0] * (e[1][1] * e[2][2] - e[2][1] * e[1][2])
            - e[1][0] * (e[0][1] * e[2][2] - e[2][1] * e[0][2])
            + e[2][0] * (e[0][1] * e[1][2] - e[1][1] * e[0][2]);
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
        };
        let rows = [cross(e[1], e[2]), cross(e[2], e[0]), cross(e[0], e[1])].map(|r| r.map(|x| x / det));
        let mut g = [[0.0; 3]; 4];
        for a in 0..3 {
            g[a + 1] = rows[a];
            for i in 0..3 {
                g[0][i] -= rows[a][i];
            }
        }
        let volume = det.abs() / 6.0;
        for (ta, &ca) in tet.iter().enumerate() {
            for (tb, &cb) in tet.iter().enumerate() {
                let (ga, gb) = (g[ta], g[tb]);
                let dot = ga[0] * gb[0] + ga[1] * gb[1] + ga[2] * gb[2];
                let block = &mut k[ca * 8 + cb];
                for i in 0..3 {
                    for j in 0..3 {
                        let mut v = lambda * ga[i] * gb[j] + mu * ga[j] * gb[i];
                        if i == j {
                            v += mu * dot;
                        }
                        block[i * 3 + j] += volume * v;
                    }
                }
            }
        }
    }
    k.map(|b| b.map(|x| x as f32))
}

impl Body {
    /// Whether this body may have elastic cells: a grid volume with a material that has a Poisson's
    /// ratio. Its sweeps then go in place, through [`Body::relaxed_elastic`].
    pub(crate) fn has_elastic(&self) -> bool {
        self.lattice.dims.is_some_and(|d| d.iter().all(|&n| n >= 2))
            && self.materials.iter().any(|m| m.poisson_ratio.is_some())
    }

    /// The links' materials and breaks the elastic cells depend on, as they are now.
    fn cells_key(&self) -> Option<(u64, u64)> {
        Some((self.boxes_epoch, self.broken))
    }

    /// Whether the body has elastic cells, found for its links as they are now.
    fn cells_current(&self) -> bool {
        self.elastic.any && self.elastic.found_at == self.cells_key()
    }

    /// Finds the elastic cells again if the body changed since they were found.
    pub(crate) fn refresh_elastic(&mut self) {
        let now = self.cells_key();
        if self.elastic.found_at == now {
            return;
        }
        let mut el = std::mem::take(&mut self.elastic);
        el.found_at = now;
        el.any = false;
        el.cell.clear();
        el.dims = [0; 3];
        let dims = match self.lattice.dims {
            Some(d) if self.has_elastic() => d,
            _ => {
                self.elastic = el;
                return;
            }
        };
        el.dims = dims;
        let [nx, ny, nz] = dims;
        let at = |x: usize, y: usize, z: usize| x + nx * (y + ny * z);
        let lattice = &self.lattice;
        // The link from `a` to its neighbour `b`, if any.
        let link = |a: usize, b: usize| {
            let (s0, s1) = (lattice.adj_start[a] as usize, lattice.adj_start[a + 1] as usize);
            (s0..s1).find(|&s| lattice.adj_nbr[s] as usize == b).map(|s| lattice.adj_link[s] as usize)
        };
        for z in 0..nz - 1 {
            for y in 0..ny - 1 {
                for x in 0..nx - 1 {
                    let corner = |c: usize| at(x + (c & 1), y + ((c >> 1) & 1), z + ((c >> 2) & 1));
                    let mut edges = [usize::MAX; 12];
                    let mut n = 0;
                    for c in 0..8 {
                        for axis in 0..3 {
                            if (c >> axis) & 1 == 0 {
                                edges[n] = link(corner(c), corner(c | (1 << axis))).unwrap_or(usize::MAX);
                                n += 1;
                            }
                        }
                    }
                    let intact = edges.iter().all(|&l| l != usize::MAX && self.link_state[l] == INTACT);
                    let material = intact.then(|| self.materials[self.link_material[edges[0]].index()]);
                    let class = match material.and_then(|m| m.poisson_ratio.map(|nu| (m, nu))) {
                        Some((material, nu)) => {
                            let r = &lattice.rest;
                            // (To a tenth of a micrometre: the cells of an even grid, whose rest
                            // positions' rounding differs in the last bits, share one stiffness and
                            // their elements a handful of stencils.)
                            let side = [1, 2, 4].map(|c| {
                                let (p, q) = (r[corner(0)], r[corner(c)]);
                                let d = [0, 1, 2].map(|k| f64::from(q[k]) - f64::from(p[k]));
                                ((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() * 1e7).round() * 1e-7
                            });
                            let scale = f64::from(material.young_modulus) * f64::from(material.stiffness);
                            let key = [
                                nu.to_bits(),
                                (scale as f32).to_bits(),
                                (side[0] as f32).to_bits(),
                                (side[1] as f32).to_bits(),
                                (side[2] as f32).to_bits(),
                            ];
                            let next = el.stiffness.len() as u32;
                            let id = *el.index.entry(key).or_insert(next);
                            if id == next {
                                el.stiffness.push(cell_stiffness(side, f64::from(nu), scale));
                            }
                            el.any = true;
                            id
                        }
                        _ => NONE,
                    };
                    el.cell.push(class);
                }
            }
        }
        el.element.clear();
        el.element.resize(nx * ny * nz, NONE);
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    // The element is corner `a` of the cell whose lowest corner lies `a` back from it.
                    let key = std::array::from_fn(|a| {
                        // (Wrapped below zero, a cell outside the block is out of range.)
                        let cx = x.wrapping_sub(a & 1);
                        let cy = y.wrapping_sub((a >> 1) & 1);
                        let cz = z.wrapping_sub((a >> 2) & 1);
                        match cx < nx - 1 && cy < ny - 1 && cz < nz - 1 {
                            true => el.cell[cx + (nx - 1) * (cy + (ny - 1) * cz)],
                            false => NONE,
                        }
                    });
                    if key.iter().all(|&k| k == NONE) {
                        continue;
                    }
                    let next = el.stencil.len() as u32;
                    let id = *el.stencil_index.entry(key).or_insert(next);
                    if id == next {
                        el.stencil.push(stencil_of(&key, &el.stiffness, dims));
                    }
                    el.element[at(x, y, z)] = id;
                }
            }
        }
        self.elastic = el;
    }

    /// Element `i`'s elastic update (see the module docs), positions read through `pos_of`, boxed by
    /// `lo` and `hi` (the intersection of its link boxes); `None` where the element lies in no elastic
    /// cell (or is fixed).
    #[inline]
    pub(crate) fn relaxed_elastic(
        &self,
        i: usize,
        p: [f32; 3],
        lo: [f32; 3],
        hi: [f32; 3],
        pos_of: impl Fn(usize) -> [f32; 3],
    ) -> Option<[f32; 3]> {
        let el = &self.elastic;
        if !self.cells_current() || self.flags[i] & FIXED != 0 {
            return None;
        }
        let (g, d) = match el.element[i] {
            NONE => return None,
            id => self.elastic_stencil(i, p, id, &pos_of),
        };
        Some(project(p, g, d, lo, hi))
    }

    /// The energy's gradient at element `i` and its diagonal block, from its stencil `id`: the
    /// blocks times the neighbours' displacements less the element's (the blocks sum to zero, as no
    /// translation strains a cell), so that the tissue at rest feels exactly nothing. The same as
    /// [`Body::elastic_cells`] up to rounding (tested below).
    #[inline]
    pub(crate) fn elastic_stencil(
        &self,
        i: usize,
        p: [f32; 3],
        id: u32,
        pos_of: impl Fn(usize) -> [f32; 3],
    ) -> ([f32; 3], [f32; 9]) {
        let el = &self.elastic;
        let st = &el.stencil[id as usize];
        let rest = &self.lattice.rest;
        let ri = rest[i];
        let ui = [p[0] - ri[0], p[1] - ri[1], p[2] - ri[2]];
        let mut g = [0.0f32; 3];
        for (off, block) in &st.entries {
            // (Only neighbours that exist have entries.)
            let j = i.wrapping_add_signed(*off);
            let (q, r) = (pos_of(j), rest[j]);
            let u = [(q[0] - r[0]) - ui[0], (q[1] - r[1]) - ui[1], (q[2] - r[2]) - ui[2]];
            for r in 0..3 {
                g[r] += block[r * 3] * u[0] + block[r * 3 + 1] * u[1] + block[r * 3 + 2] * u[2];
            }
        }
        (g, st.diag)
    }

    /// The force that holds the elements of `set` where they are against the elastic cells, summed
    /// (`K u` over the set: newtons in a volume whose lattice is in metres); `None` where the body has
    /// no elastic cells found for its present links and materials (before its first sweep, or after a
    /// cut until the next), or none of the set lies in one.
    pub fn elastic_force(&self, set: &[ElementId]) -> Option<[f32; 3]> {
        if !self.cells_current() {
            return None;
        }
        let el = &self.elastic;
        let mut f = [0.0f32; 3];
        let mut any = false;
        for &e in set {
            let i = e.index();
            let Some(&id) = el.element.get(i) else { continue };
            if id == NONE {
                continue;
            }
            any = true;
            let (g, _) = self.elastic_stencil(i, self.pos[i], id, |j| self.pos[j]);
            f = [f[0] + g[0], f[1] + g[1], f[2] + g[2]];
        }
        any.then_some(f)
    }

    /// The energy's gradient at element `i` and its diagonal block, summed over its elastic cells
    /// (the reference); `None` where it lies in none.
    #[cfg(test)]
    pub(crate) fn elastic_cells(
        &self,
        i: usize,
        p: [f32; 3],
        pos_of: impl Fn(usize) -> [f32; 3],
    ) -> Option<([f32; 3], [f32; 9])> {
        let el = &self.elastic;
        let [nx, ny, nz] = el.dims;
        let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
        let rest = &self.lattice.rest;
        let mut g = [0.0f32; 3];
        let mut d = [0.0f32; 9];
        let mut found = false;
        for cz in z.saturating_sub(1)..=z.min(nz - 2) {
            for cy in y.saturating_sub(1)..=y.min(ny - 2) {
                for cx in x.saturating_sub(1)..=x.min(nx - 2) {
                    let class = el.cell[cx + (nx - 1) * (cy + (ny - 1) * cz)];
                    if class == NONE {
                        continue;
                    }
                    found = true;
                    let k = &el.stiffness[class as usize];
                    let a = (x - cx) | ((y - cy) << 1) | ((z - cz) << 2);
                    for b in 0..8 {
                        let j = cx + (b & 1) + nx * (cy + ((b >> 1) & 1) + ny * (cz + ((b >> 2) & 1)));
                        let q = if j == i { p } else { pos_of(j) };
                        let u = [0, 1, 2].map(|c| q[c] - rest[j][c]);
                        let block = &k[a * 8 + b];
                        for r in 0..3 {
                            g[r] += block[r * 3] * u[0] + block[r * 3 + 1] * u[1] + block[r * 3 + 2] * u[2];
                        }
                        if b == a {
                            for (s, v) in d.iter_mut().zip(block) {
                                *s += v;
                            }
                        }
                    }
                }
            }
        }
        found.then_some((g, d))
    }
}

/// The stencil of an element that is corner `a` of a cell of stiffness `key[a]` (`NONE`: no cell).
fn stencil_of(key: &[u32; 8], stiffness: &[CellStiffness], dims: [usize; 3]) -> Stencil {
    let mut block = [[0.0f32; 9]; 27];
    let mut mask = 0u32;
    for (a, &class) in key.iter().enumerate() {
        if class == NONE {
            continue;
        }
        let k = &stiffness[class as usize];
        for b in 0..8 {
            let off = [0, 1, 2].map(|c| ((b >> c) & 1) as i32 - ((a >> c) & 1) as i32);
            let o = ((off[0] + 1) + 3 * (off[1] + 1) + 9 * (off[2] + 1)) as usize;
            let kb = &k[a * 8 + b];
            for (s, v) in block[o].iter_mut().zip(kb) {
                *s += v;
            }
            if o != 13 {
                mask |= 1 << o;
            }
        }
    }
    let [nx, ny, _] = dims.map(|d| d as isize);
    let entries = (0..27)
        .filter(|&o| mask & (1 << o) != 0 && block[o].iter().any(|&v| v != 0.0))
        .map(|o| {
            let off = (o % 3) as isize - 1 + nx * ((o / 3) % 3) as isize - nx + nx * ny * (o / 9) as isize
                - nx * ny;
            (off, block[o])
        })
        .collect();
    Stencil { diag: block[13], entries }
}

/// The projected coordinate steps of an element at `p` with energy gradient `g` and diagonal block
/// `d`: each coordinate to the energy's minimum along it, within `[min(lo, p), max(hi, p)]`.
#[inline(always)]
fn project(p: [f32; 3], mut g: [f32; 3], d: [f32; 9], lo: [f32; 3], hi: [f32; 3]) -> [f32; 3] {
    {
        let mut q = p;
        for c in 0..3 {
            let dc = d[c * 3 + c];
            if dc <= 0.0 {
                continue;
            }
            let floor = if lo[c] < q[c] { lo[c] } else { q[c] };
            let ceil = if hi[c] > q[c] { hi[c] } else { q[c] };
            let t = clamp(q[c] - g[c] / dc, floor, ceil);
            let t = (t + FLUSH) - FLUSH;
            let step = t - q[c];
            q[c] = t;
            for r in 0..3 {
                g[r] += d[r * 3 + c] * step;
            }
        }
        q
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chainmail::{
        BreakReason, Lattice, LinkId, Material, Pass, RelaxBudget, RelaxRegion, Workspace,
    };

    /// A 6 × 5 × 7 block of elastic cells (ν = 0.45), its base pinned, with a second material (a
    /// stiffer ν = 0.3) in one corner and a cut through three links: the shared stencils meet every
    /// kind of element (interior, faces, edges, corners, between materials, beside the cut).
    fn block() -> Body {
        let lattice = Lattice::volume(6, 5, 7, 0.01).expect("lattice");
        let soft = Material { poisson_ratio: Some(0.45), ..Material::relative(1.3, 0.7, 0.4) };
        let mut body = Body::new(lattice, soft).expect("body");
        let stiff = body
            .add_material(Material {
                poisson_ratio: Some(0.3),
                young_modulus: 3.0e6,
                ..Material::relative(1.2, 0.8, 0.3)
            })
            .expect("material");
        body.set_material_where(stiff, |a, b| a[0] > 0.025 && b[0] > 0.025 && a[2] > 0.035).expect("region");
        for l in [40, 41, 97] {
            body.break_link(LinkId(l), BreakReason::Cut).expect("cut");
        }
        for e in 0..body.element_count() {
            if body.lattice().rest_positions()[e][1] == 0.0 {
                body.set_pinned(ElementId(e as u32), true).expect("pin");
            }
        }
        body
    }

    #[test]
    fn the_stencils_are_the_cells() {
        let mut body = block();
        body.refresh_elastic();
        let n = body.element_count();
        // A smooth but not uniform displacement, a few millimetres.
        for e in 0..n {
            let r = body.lattice().rest_positions()[e];
            let u = [0.3 * r[1] * r[2], -0.2 * r[0] * r[0] * 10.0, 0.1 * (r[0] + r[1]) * r[2] * 10.0];
            body.set_position(ElementId(e as u32), [0, 1, 2].map(|k| r[k] + u[k])).expect("move");
        }
        let (mut largest, mut compared) = (0.0f32, 0);
        for i in 0..n {
            let p = body.pos[i];
            let cells = body.elastic_cells(i, p, |j| body.pos[j]);
            let id = body.elastic.element[i];
            assert_eq!(cells.is_none(), id == NONE, "element {i}");
            let Some((g, d)) = cells else { continue };
            let (gs, ds) = body.elastic_stencil(i, p, id, |j| body.pos[j]);
            largest = largest.max(g.iter().fold(0.0f32, |m, x| m.max(x.abs())));
            for k in 0..3 {
                assert!(
                    (g[k] - gs[k]).abs() <= 2e-3 * (1.0 + g[k].abs()),
                    "element {i}: {g:?} against {gs:?}"
                );
            }
            for (a, b) in d.iter().zip(&ds) {
                assert!((a - b).abs() <= 1e-4 * (1.0 + a.abs()), "element {i}: {d:?} against {ds:?}");
            }
            compared += 1;
        }
        assert!(compared > n / 2 && largest > 1.0, "{compared} of {n}, largest force {largest}");
        assert!(body.elastic.stencil.len() > 27, "{} stencils", body.elastic.stencil.len());
    }

    #[test]
    fn relaxed_cells_keep_the_limits_and_rest_comes_back() {
        let mut body = block();
        let mut ws = Workspace::new(&body);
        let top = body.lattice().element_at(3, 4, 3).expect("top");
        let r = body.lattice().rest_positions()[top.index()];
        body.deform(&mut ws, top, [r[0] + 0.004, r[1] + 0.015, r[2] - 0.003], Pass::All).expect("pull");
        body.set_held(top, true).expect("hold");
        let worst = |body: &Body| {
            (0..body.link_count())
                .filter(|&l| body.link_intact(LinkId(l as u32)))
                .map(|l| body.link_violation(LinkId(l as u32)).unwrap_or(0.0))
                .fold(0.0f32, f32::max)
        };
        let before = worst(&body);
        let report = body.relax(
            &mut ws,
            RelaxBudget { max_sweeps: 3000, max_time: None, tolerance: 1e-9 },
            RelaxRegion::All,
        );
        assert!(report.sweeps > 10, "{report:?}");
        assert!(worst(&body) <= before + 1e-6, "limits: {} after, {before} before", worst(&body));
        // Its force holds the pulled element up and toward where it was pulled.
        let f = body.elastic_force(&[top]).expect("force");
        assert!(f[1] > 0.0, "{f:?}");
        // Let go, it goes back to rest.
        body.set_held(top, false).expect("release");
        body.relax(
            &mut ws,
            RelaxBudget { max_sweeps: 20_000, max_time: None, tolerance: 1e-9 },
            RelaxRegion::All,
        );
        let off = (0..body.element_count())
            .map(|e| {
                let (p, r) = (body.positions()[e], body.lattice().rest_positions()[e]);
                (0..3).map(|k| (p[k] - r[k]).abs()).fold(0.0f32, f32::max)
            })
            .fold(0.0f32, f32::max);
        assert!(off < 1e-5, "{off} m from rest");
    }

    /// At rest every element feels exactly nothing (whatever the rounding of its rest position and of
    /// the cells' sides), so nothing at rest ever moves or joins a region.
    #[test]
    fn rest_is_exactly_balanced() {
        let lattice = Lattice::grid(&crate::chainmail::GridSpec::uniform([9, 7, 8], 0.0013)).expect("grid");
        let mut body =
            Body::new(lattice, Material { poisson_ratio: Some(0.45), ..Material::default() }).expect("body");
        body.refresh_elastic();
        for i in 0..body.element_count() {
            let id = body.elastic.element[i];
            let (g, _) = body.elastic_stencil(i, body.pos[i], id, |j| body.pos[j]);
            assert_eq!(g, [0.0; 3], "element {i}");
        }
        assert!(body.elastic.stencil.len() <= 27, "{} stencils on an even grid", body.elastic.stencil.len());
    }

    #[test]
    fn sheets_have_no_cells() {
        let lattice = Lattice::volume(6, 5, 1, 0.01).expect("sheet");
        let mut body =
            Body::new(lattice, Material { poisson_ratio: Some(0.45), ..Material::default() }).expect("body");
        assert!(!body.has_elastic());
        body.refresh_elastic();
        assert!(body.elastic_force(&[ElementId(3)]).is_none());
    }

    #[test]
    fn a_cell_has_no_energy_in_rigid_motion_and_the_moduli_in_uniform_strain() {
        let side = [0.5, 1.0, 2.0];
        let (nu, e) = (0.3, 2.0);
        let k = cell_stiffness(side, nu, e);
        let corner = |c: usize| [0, 1, 2].map(|a| if (c >> a) & 1 == 1 { side[a] as f32 } else { 0.0 });
        let force = |u: &dyn Fn([f32; 3]) -> [f32; 3]| {
            (0..8)
                .map(|a| {
                    let mut f = [0.0f32; 3];
                    for b in 0..8 {
                        let ub = u(corner(b));
                        for r in 0..3 {
                            for c in 0..3 {
                                f[r] += k[a * 8 + b][r * 3 + c] * ub[c];
                            }
                        }
                    }
                    f
                })
                .collect::<Vec<_>>()
        };
        // A translation and a small rotation about z: no force anywhere.
        for f in force(&|_| [0.3, -0.2, 0.1]).into_iter().chain(force(&|p| [-p[1], p[0], 0.0])) {
            assert!(f.iter().all(|x| x.abs() < 1e-5), "{f:?}");
        }
        // Uniform strain εxx = s with the sides free: the x faces carry σxx = (λ + 2μ) s over their
        // area, split over their four corners.
        let s = 0.01f32;
        let f = force(&|p| [s * p[0], 0.0, 0.0]);
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let mu = e / (2.0 * (1.0 + nu));
        let total: f32 = (0..8).filter(|c| c & 1 == 1).map(|c| f[c][0]).sum();
        let expected = ((lambda + 2.0 * mu) * f64::from(s) * side[1] * side[2]) as f32;
        assert!((total - expected).abs() < 1e-4 * expected.abs(), "{total} against {expected}");
    }
}
