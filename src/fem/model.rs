//! The condensed model: supports, degrees of freedom numbered surface first, the sparse global
//! stiffness, the Schur complement onto the free surface nodes and its explicit inverse, and the
//! run-time operations on it (selective matrix-vector multiplication, imposed displacements).

use faer::linalg::solvers::{DenseSolveCore, SolveCore};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, Mat, Side};

use super::element::tet_stiffness;
use super::error::{FemError, finite};
use super::material::ElasticMaterial;
use super::mesh::{Face, NodeId, TetId, TetMesh};

/// Default limit on the dense matrices kept by a model: 512 MiB.
pub const DEFAULT_MEMORY_LIMIT: usize = 512 << 20;

/// Marks a fixed degree of freedom in the dof table.
const FIXED: u32 = u32::MAX;

/// Columns of the Schur complement computed per sparse solve.
const SCHUR_CHUNK: usize = 64;

/// Scratch of [`FemModel::impose_with`]: the imposed dofs, the block of the condensed inverse over
/// them and its Cholesky factor's workspace, the right-hand side (then the forces at those dofs) and
/// the forces per node. Kept between calls, it grows to the most dofs imposed and no further.
#[derive(Clone, Debug, Default)]
pub struct ImposeWork {
    dofs: Vec<usize>,
    rhs: Vec<f64>,
    block: Vec<f64>,
    stack: Vec<std::mem::MaybeUninit<u8>>,
    forces: Vec<[f64; 3]>,
}

/// Options of [`FemModel::load`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadOptions {
    /// Most bytes the dense matrices of the model may take: the condensed stiffness `S` and its
    /// inverse, `2 · n² · 8` bytes for `n` condensed degrees of freedom. Default 512 MiB
    /// ([`DEFAULT_MEMORY_LIMIT`]). A block of 16³ nodes clamped at its base needs about 165 MiB.
    pub memory_limit: usize,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self { memory_limit: DEFAULT_MEMORY_LIMIT }
    }
}

/// How the base of a block (the y = 0 face) is held.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Base {
    /// Every base node fixed in x, y and z.
    Clamped,
    /// Base nodes fixed in y only, free to slide in x and z, plus the least more to stop rigid motion:
    /// node (0, 0, 0) fixed in x and z, node (nx − 1, 0, 0) fixed in z.
    Rollers,
}

/// Which degrees of freedom are fixed (zero displacement): the boundary conditions.
#[derive(Clone, Debug, PartialEq)]
pub struct Supports {
    fixed: Vec<[bool; 3]>,
}

impl Supports {
    /// No node fixed (a model needs some supports to be loaded).
    pub fn none(mesh: &TetMesh) -> Self {
        Self { fixed: vec![[false; 3]; mesh.node_count()] }
    }

    /// The base of the block held as `base`.
    pub fn base(mesh: &TetMesh, base: Base) -> Self {
        let mut s = Self::none(mesh);
        for n in 0..mesh.node_count() {
            if mesh.on_face(NodeId(n as u32), Face::YMin) {
                s.fixed[n] = match base {
                    Base::Clamped => [true; 3],
                    Base::Rollers => [false, true, false],
                };
            }
        }
        if base == Base::Rollers {
            let [nx, _, _] = mesh.dims();
            if let Some(o) = mesh.node_at(0, 0, 0) {
                s.fixed[o.index()] = [true; 3];
            }
            if let Some(x) = mesh.node_at(nx - 1, 0, 0) {
                s.fixed[x.index()][2] = true;
            }
        }
        s
    }

    /// Fixes (or frees) the given axes of a node.
    pub fn fix(&mut self, node: NodeId, axes: [bool; 3]) -> Result<(), FemError> {
        let count = self.fixed.len();
        let slot = self.fixed.get_mut(node.index()).ok_or(FemError::NodeOutOfRange { id: node.0, count })?;
        *slot = axes;
        Ok(())
    }

    /// The fixed axes of a node.
    pub fn fixed(&self, node: NodeId) -> Option<[bool; 3]> {
        self.fixed.get(node.index()).copied()
    }
}

/// A sparse matrix in compressed columns, for the surface–interior coupling `K_is`.
#[derive(Clone, Debug, Default)]
struct Csc {
    col_start: Vec<usize>,
    row: Vec<u32>,
    val: Vec<f64>,
}

/// A linear elastic tetrahedral model condensed onto its free surface nodes (Bro-Nielsen and Cotin).
///
/// Degrees of freedom are numbered free surface nodes first (the *condensed* dofs, `0..n`), interior
/// ones after. At load time the interior is eliminated, `S = K_ss − K_si K_ii⁻¹ K_is`, and `S⁻¹` is
/// computed once; at run time the surface displacement for forces on a few nodes is a selective
/// matrix-vector product over the non-zero forces.
#[derive(Clone, Debug)]
pub struct FemModel {
    mesh: TetMesh,
    material: ElasticMaterial,
    /// Global free dof of every node axis, surface dofs first; [`FIXED`] when fixed.
    dof: Vec<[u32; 3]>,
    n_s: usize,
    n_i: usize,
    surface_nodes: Vec<NodeId>,
    /// Free–free stiffness, merged triplets `(row, col, value)` sorted by column then row.
    stiffness: Vec<(u32, u32, f64)>,
    k_is: Csc,
    interior: Option<faer::sparse::linalg::solvers::Llt<usize, f64>>,
    condensed: Mat<f64>,
    inverse: Mat<f64>,
    mass: Vec<f64>,
}

fn mib(bytes: f64) -> f64 {
    bytes / (1u64 << 20) as f64
}

fn sparse_llt(
    n: usize,
    entries: &[Triplet<usize, usize, f64>],
    which: &'static str,
) -> Result<faer::sparse::linalg::solvers::Llt<usize, f64>, FemError> {
    let mat = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, entries)
        .map_err(|e| FemError::Backend(format!("{e:?}")))?;
    mat.sp_cholesky(Side::Lower).map_err(|e| FemError::Singular { which, detail: format!("{e:?}") })
}

impl FemModel {
    /// Builds and condenses the model: element stiffness, sparse assembly, sparse Cholesky of the
    /// interior block, the Schur complement onto the free surface nodes, and its dense inverse.
    ///
    /// `progress` is called with a fraction in `[0, 1]` as the work goes on (the last call is 1). The
    /// load is refused with [`FemError::TooBig`] before anything large is allocated when the dense
    /// matrices would exceed `options.memory_limit`.
    pub fn load(
        mesh: TetMesh,
        material: ElasticMaterial,
        supports: &Supports,
        options: &LoadOptions,
        mut progress: impl FnMut(f32),
    ) -> Result<Self, FemError> {
        material.validate()?;
        let n = mesh.node_count();
        if supports.fixed.len() != n {
            return Err(FemError::WrongLength { what: "supports", got: supports.fixed.len(), expected: n });
        }
        progress(0.0);
        // Number the dofs: free surface nodes first.
        let mut dof = vec![[FIXED; 3]; n];
        let mut next = 0u32;
        let mut surface_nodes = Vec::new();
        for boundary in [true, false] {
            for (node, d) in dof.iter_mut().enumerate() {
                let id = NodeId(node as u32);
                if mesh.is_boundary(id) != boundary {
                    continue;
                }
                let fixed = supports.fixed[node];
                if boundary && fixed.contains(&false) {
                    surface_nodes.push(id);
                }
                for a in 0..3 {
                    if !fixed[a] {
                        d[a] = next;
                        next += 1;
                    }
                }
            }
            if boundary && next == 0 {
                return Err(FemError::NoSurface);
            }
        }
        let n_s = surface_nodes.iter().map(|s| dof[s.index()].iter().filter(|&&d| d != FIXED).count()).sum();
        let n_i = next as usize - n_s;
        let dense = 2.0 * (n_s as f64) * (n_s as f64) * 8.0;
        let chunk = (n_i * SCHUR_CHUNK * 8) as f64;
        if dense + chunk > options.memory_limit as f64 {
            return Err(FemError::TooBig {
                what: format!(
                    "the dense condensed inverse ({n_s} × {n_s} f64, {:.1} MiB) with the condensed stiffness \
                     kept beside it",
                    mib(dense / 2.0)
                ),
                needed_mib: mib(dense + chunk),
                limit_mib: mib(options.memory_limit as f64),
            });
        }

        // Element stiffness and sparse assembly of the free–free block.
        let d = material.d_matrix();
        let mut mass = vec![0.0; n];
        let mut trip: Vec<(u32, u32, f64)> = Vec::with_capacity(mesh.tet_count() * 144);
        for (t, tet) in mesh.tets().iter().enumerate() {
            let p = tet.map(|v| mesh.positions()[v as usize]);
            let (ke, volume) = tet_stiffness(t, &p, &d)?;
            for &v in tet {
                mass[v as usize] += material.density * volume / 4.0;
            }
            for a in 0..12 {
                let r = dof[tet[a / 3] as usize][a % 3];
                if r == FIXED {
                    continue;
                }
                for b in 0..12 {
                    let c = dof[tet[b / 3] as usize][b % 3];
                    if c != FIXED {
                        trip.push((r, c, ke[(a, b)]));
                    }
                }
            }
        }
        trip.sort_unstable_by_key(|&(r, c, _)| (c, r));
        let mut stiffness: Vec<(u32, u32, f64)> = Vec::with_capacity(trip.len() / 4);
        for (r, c, v) in trip {
            match stiffness.last_mut() {
                Some(last) if last.0 == r && last.1 == c => last.2 += v,
                _ => stiffness.push((r, c, v)),
            }
        }
        progress(0.1);

        // Split into blocks: K_ss dense (it becomes S), K_is compressed, K_ii for the sparse Cholesky.
        let mut condensed = Mat::<f64>::zeros(n_s, n_s);
        let mut k_is = Csc { col_start: vec![0; n_s + 1], ..Csc::default() };
        let mut k_ii = Vec::new();
        for &(r, c, v) in &stiffness {
            let (r, c) = (r as usize, c as usize);
            match (r < n_s, c < n_s) {
                (true, true) => condensed.col_as_slice_mut(c)[r] += v,
                (false, true) => {
                    k_is.row.push((r - n_s) as u32);
                    k_is.val.push(v);
                    k_is.col_start[c + 1] += 1;
                }
                (false, false) => k_ii.push(Triplet::new(r - n_s, c - n_s, v)),
                (true, false) => {}
            }
        }
        for c in 0..n_s {
            k_is.col_start[c + 1] += k_is.col_start[c];
        }
        let interior = if n_i > 0 { Some(sparse_llt(n_i, &k_ii, "interior")?) } else { None };
        drop(k_ii);
        progress(0.15);

        // Schur complement S = K_ss − K_isᵀ K_ii⁻¹ K_is, a block of columns at a time.
        if let Some(llt) = &interior {
            let mut x = Mat::<f64>::zeros(n_i, SCHUR_CHUNK);
            for c0 in (0..n_s).step_by(SCHUR_CHUNK) {
                let w = SCHUR_CHUNK.min(n_s - c0);
                for j in 0..w {
                    let col = x.col_as_slice_mut(j);
                    col.fill(0.0);
                    for k in k_is.col_start[c0 + j]..k_is.col_start[c0 + j + 1] {
                        col[k_is.row[k] as usize] = k_is.val[k];
                    }
                }
                llt.solve_in_place_with_conj(Conj::No, x.as_mut().subcols_mut(0, w));
                for j in 0..w {
                    let xj = x.col_as_slice(j);
                    let sj = condensed.col_as_slice_mut(c0 + j);
                    for (a, s) in sj.iter_mut().enumerate() {
                        let mut acc = 0.0;
                        for k in k_is.col_start[a]..k_is.col_start[a + 1] {
                            acc += k_is.val[k] * xj[k_is.row[k] as usize];
                        }
                        *s -= acc;
                    }
                }
                progress(0.15 + 0.65 * ((c0 + w) as f32 / n_s as f32));
            }
        }
        progress(0.8);

        // The explicit inverse of the condensed stiffness.
        let llt = condensed
            .llt(Side::Lower)
            .map_err(|e| FemError::Singular { which: "condensed", detail: format!("{e:?}") })?;
        let inverse = llt.inverse();
        drop(llt);
        // A Cholesky factorisation can pass on a singular matrix by rounding (tiny positive pivots
        // where rigid motions should give zero): catch it by the size of the inverse.
        let max_abs = |m: &Mat<f64>| {
            (0..m.ncols()).flat_map(|j| m.col_as_slice(j)).fold(0.0f64, |a, &x| a.max(x.abs()))
        };
        let condition = max_abs(&condensed) * max_abs(&inverse);
        if !(condition.is_finite() && condition < 1e12) {
            return Err(FemError::Singular {
                which: "condensed",
                detail: format!("max|S| · max|S⁻¹| = {condition:e}"),
            });
        }
        progress(1.0);
        Ok(Self {
            mesh,
            material,
            dof,
            n_s,
            n_i,
            surface_nodes,
            stiffness,
            k_is,
            interior,
            condensed,
            inverse,
            mass,
        })
    }

    /// The mesh.
    pub fn mesh(&self) -> &TetMesh {
        &self.mesh
    }

    /// The material.
    pub fn material(&self) -> &ElasticMaterial {
        &self.material
    }

    /// Free surface nodes (boundary nodes with at least one free axis), in condensed order.
    pub fn surface_nodes(&self) -> &[NodeId] {
        &self.surface_nodes
    }

    /// Number of condensed degrees of freedom (free axes of the free surface nodes): the length of a
    /// condensed displacement or force vector.
    pub fn condensed_dofs(&self) -> usize {
        self.n_s
    }

    /// Number of interior degrees of freedom eliminated by the condensation.
    pub fn interior_dofs(&self) -> usize {
        self.n_i
    }

    /// Bytes held by the dense condensed stiffness and its inverse.
    pub fn dense_bytes(&self) -> usize {
        2 * self.n_s * self.n_s * 8
    }

    /// The condensed dof of a node's axis, if the node is a free surface node and the axis is free.
    pub fn condensed_dof(&self, node: NodeId, axis: usize) -> Option<usize> {
        let d = *self.dof.get(node.index())?.get(axis)?;
        (d != FIXED && (d as usize) < self.n_s).then_some(d as usize)
    }

    /// Column `j` of the condensed inverse `S⁻¹`: the surface displacement under a unit force on
    /// condensed dof `j`.
    pub fn inverse_column(&self, j: usize) -> Option<&[f64]> {
        (j < self.n_s).then(|| self.inverse.col_as_slice(j))
    }

    /// Column `j` of the condensed stiffness `S`.
    pub fn condensed_column(&self, j: usize) -> Option<&[f64]> {
        (j < self.n_s).then(|| self.condensed.col_as_slice(j))
    }

    /// Lumped nodal masses (a quarter of each tetrahedron's mass on each corner), kg.
    pub fn nodal_masses(&self) -> &[f64] {
        &self.mass
    }

    pub(crate) fn dof_table(&self) -> &[[u32; 3]] {
        &self.dof
    }

    fn check_len(&self, what: &'static str, len: usize) -> Result<(), FemError> {
        if len == self.n_s {
            Ok(())
        } else {
            Err(FemError::WrongLength { what, got: len, expected: self.n_s })
        }
    }

    fn surface_dofs(&self, node: NodeId) -> Result<[u32; 3], FemError> {
        let d = *self
            .dof
            .get(node.index())
            .ok_or(FemError::NodeOutOfRange { id: node.0, count: self.dof.len() })?;
        if d.iter().all(|&x| x == FIXED) {
            return Err(FemError::NotSurfaceNode { id: node.0, reason: "every axis of it is fixed" });
        }
        if d.iter().any(|&x| x != FIXED && x as usize >= self.n_s) {
            return Err(FemError::NotSurfaceNode {
                id: node.0,
                reason: "it is an interior node, eliminated by the condensation",
            });
        }
        Ok(d)
    }

    /// The full product `u = S⁻¹ f` over every condensed dof (the reference for
    /// [`multiply_selective`](Self::multiply_selective)).
    pub fn multiply_full(&self, f: &[f64], u: &mut [f64]) -> Result<(), FemError> {
        self.check_len("force vector", f.len())?;
        self.check_len("displacement vector", u.len())?;
        u.fill(0.0);
        for (j, &fj) in f.iter().enumerate() {
            for (ui, &c) in u.iter_mut().zip(self.inverse.col_as_slice(j)) {
                *ui += c * fj;
            }
        }
        Ok(())
    }

    /// Selective matrix-vector multiplication: `u = S⁻¹ f` for a force vector given by its non-zero
    /// entries `(condensed dof, force in newtons)`; costs `n` per non-zero force instead of `n²`.
    pub fn multiply_selective(&self, forces: &[(usize, f64)], u: &mut [f64]) -> Result<(), FemError> {
        self.check_len("displacement vector", u.len())?;
        u.fill(0.0);
        for &(j, fj) in forces {
            finite("force", fj)?;
            let col = self.inverse_column(j).ok_or(FemError::WrongLength {
                what: "force dof index",
                got: j,
                expected: self.n_s,
            })?;
            if fj != 0.0 {
                for (ui, &c) in u.iter_mut().zip(col) {
                    *ui += c * fj;
                }
            }
        }
        Ok(())
    }

    /// Static mode: the surface displacement `u` (condensed dofs, metres) under forces (newtons) on a
    /// few free surface nodes, by selective multiplication. Force components on fixed axes are ignored.
    pub fn apply_forces(&self, forces: &[(NodeId, [f64; 3])], u: &mut [f64]) -> Result<(), FemError> {
        self.check_len("displacement vector", u.len())?;
        for (node, f) in forces {
            self.surface_dofs(*node)?;
            for &x in f {
                finite("force", x)?;
            }
        }
        u.fill(0.0);
        for (node, f) in forces {
            let d = self.dof[node.index()];
            for a in 0..3 {
                if d[a] != FIXED && f[a] != 0.0 {
                    for (ui, &c) in u.iter_mut().zip(self.inverse.col_as_slice(d[a] as usize)) {
                        *ui += c * f[a];
                    }
                }
            }
        }
        Ok(())
    }

    /// Grasp or push: imposes displacements (metres) on a few free surface nodes, with no force on the
    /// other surface nodes. Solves the small `k × k` system `(S⁻¹)_kk f_k = d_k` for the forces at the
    /// imposed dofs, then the surface displacement `u` by selective multiplication. Returns the force
    /// (newtons) the instrument applies at each imposed node, in the order given. Components on fixed
    /// axes are ignored (they stay at zero). Allocates its scratch and the returned forces: a caller
    /// that imposes every step keeps an [`ImposeWork`] and calls [`impose_with`](Self::impose_with).
    pub fn impose(&self, imposed: &[(NodeId, [f64; 3])], u: &mut [f64]) -> Result<Vec<[f64; 3]>, FemError> {
        let mut work = ImposeWork::default();
        self.impose_with(imposed, u, &mut work).map(<[[f64; 3]]>::to_vec)
    }

    /// [`impose`](Self::impose) with its scratch in `work`: allocates only when more dofs are imposed
    /// than in any earlier call with the same `work`. Returns the forces, in the order given.
    pub fn impose_with<'w>(
        &self,
        imposed: &[(NodeId, [f64; 3])],
        u: &mut [f64],
        work: &'w mut ImposeWork,
    ) -> Result<&'w [[f64; 3]], FemError> {
        self.check_len("displacement vector", u.len())?;
        let ImposeWork { dofs, rhs, block, stack, forces } = work;
        dofs.clear();
        rhs.clear();
        for (i, (node, disp)) in imposed.iter().enumerate() {
            let d = self.surface_dofs(*node)?;
            if imposed[..i].iter().any(|(m, _)| m == node) {
                return Err(FemError::DuplicateNode { id: node.0 });
            }
            for a in 0..3 {
                finite("imposed displacement", disp[a])?;
                if d[a] != FIXED {
                    dofs.push(d[a] as usize);
                    rhs.push(disp[a]);
                }
            }
        }
        let k = dofs.len();
        block.clear();
        for &c in dofs.iter() {
            let col = self.inverse.col_as_slice(c);
            block.extend(dofs.iter().map(|&r| col[r]));
        }
        let bytes = faer::linalg::cholesky::llt::factor::cholesky_in_place_scratch::<f64>(
            k,
            faer::Par::Seq,
            Default::default(),
        )
        .or(faer::linalg::cholesky::llt::solve::solve_in_place_scratch::<f64>(k, 1, faer::Par::Seq))
        .unaligned_bytes_required();
        if stack.len() < bytes {
            stack.resize(bytes, std::mem::MaybeUninit::uninit());
        }
        let mem = faer::dyn_stack::MemStack::new(stack);
        let mut a = faer::MatMut::from_column_major_slice_mut(block, k, k);
        faer::linalg::cholesky::llt::factor::cholesky_in_place(
            a.as_mut(),
            Default::default(),
            faer::Par::Seq,
            mem,
            Default::default(),
        )
        .map_err(|_| FemError::Singular {
            which: "imposed-node block of the condensed inverse",
            detail: "Cholesky failed".into(),
        })?;
        faer::linalg::cholesky::llt::solve::solve_in_place_with_conj(
            a.as_ref(),
            Conj::No,
            faer::MatMut::from_column_major_slice_mut(rhs, k, 1),
            faer::Par::Seq,
            mem,
        );
        u.fill(0.0);
        for (&j, &fj) in dofs.iter().zip(rhs.iter()) {
            for (ui, &c) in u.iter_mut().zip(self.inverse.col_as_slice(j)) {
                *ui += c * fj;
            }
        }
        forces.clear();
        let mut it = rhs.iter();
        for (node, _) in imposed {
            let d = self.dof[node.index()];
            let mut force = [0.0; 3];
            for a in 0..3 {
                if d[a] != FIXED {
                    force[a] = it.next().copied().unwrap_or(0.0);
                }
            }
            forces.push(force);
        }
        Ok(forces)
    }

    /// The displacement of a node from a condensed displacement vector: `Some` for surface nodes
    /// (fixed axes read 0) and fully fixed nodes, `None` for interior nodes (see
    /// [`full_field`](Self::full_field)).
    pub fn displacement(&self, u: &[f64], node: NodeId) -> Option<[f64; 3]> {
        let d = *self.dof.get(node.index())?;
        let mut out = [0.0; 3];
        for a in 0..3 {
            if d[a] != FIXED {
                out[a] = *u.get(d[a] as usize).filter(|_| (d[a] as usize) < self.n_s)?;
            }
        }
        Some(out)
    }

    /// Every node's displacement from the surface displacement: the interior is recovered from
    /// `K_ii u_i = −K_is u_s` (no force inside). Costs a sparse solve: for display, not every step.
    pub fn full_field(&self, u: &[f64]) -> Result<Vec<[f64; 3]>, FemError> {
        self.check_len("displacement vector", u.len())?;
        let mut inner = Mat::<f64>::zeros(self.n_i, 1);
        if let Some(llt) = &self.interior {
            let rhs = inner.col_as_slice_mut(0);
            for (a, &ua) in u.iter().enumerate() {
                for k in self.k_is.col_start[a]..self.k_is.col_start[a + 1] {
                    rhs[self.k_is.row[k] as usize] -= self.k_is.val[k] * ua;
                }
            }
            llt.solve_in_place_with_conj(Conj::No, inner.as_mut());
        }
        let ui = inner.col_as_slice(0);
        Ok(self
            .dof
            .iter()
            .map(|d| {
                d.map(|x| match x as usize {
                    _ if x == FIXED => 0.0,
                    x if x < self.n_s => u[x],
                    x => ui[x - self.n_s],
                })
            })
            .collect())
    }

    /// Reference solve without condensation: factorises the full sparse stiffness (every free dof) and
    /// returns every node's displacement under forces on any nodes. Slow; for tests and checks.
    pub fn solve_full(&self, forces: &[(NodeId, [f64; 3])]) -> Result<Vec<[f64; 3]>, FemError> {
        let n = self.n_s + self.n_i;
        let mut rhs = Mat::<f64>::zeros(n, 1);
        for (node, f) in forces {
            let d = *self
                .dof
                .get(node.index())
                .ok_or(FemError::NodeOutOfRange { id: node.0, count: self.dof.len() })?;
            for a in 0..3 {
                finite("force", f[a])?;
                if d[a] != FIXED {
                    rhs.col_as_slice_mut(0)[d[a] as usize] += f[a];
                }
            }
        }
        let entries: Vec<_> =
            self.stiffness.iter().map(|&(r, c, v)| Triplet::new(r as usize, c as usize, v)).collect();
        let llt = sparse_llt(n, &entries, "full")?;
        llt.solve_in_place_with_conj(Conj::No, rhs.as_mut());
        let x = rhs.col_as_slice(0);
        Ok(self.dof.iter().map(|d| d.map(|i| if i == FIXED { 0.0 } else { x[i as usize] })).collect())
    }

    /// Product of the full free–free stiffness with a full displacement field (every node), giving
    /// the nodal forces on free axes (0 on fixed ones). For checks of equilibrium.
    pub fn stiffness_times(&self, field: &[[f64; 3]]) -> Result<Vec<[f64; 3]>, FemError> {
        if field.len() != self.dof.len() {
            return Err(FemError::WrongLength { what: "field", got: field.len(), expected: self.dof.len() });
        }
        let n = self.n_s + self.n_i;
        let mut x = vec![0.0; n];
        for (d, v) in self.dof.iter().zip(field) {
            for a in 0..3 {
                if d[a] != FIXED {
                    x[d[a] as usize] = v[a];
                }
            }
        }
        let mut y = vec![0.0; n];
        for &(r, c, v) in &self.stiffness {
            y[r as usize] += v * x[c as usize];
        }
        Ok(self.dof.iter().map(|d| d.map(|i| if i == FIXED { 0.0 } else { y[i as usize] })).collect())
    }

    /// Cutting is refused: condensation onto the surface and the explicit inverse are computed once at
    /// load time for a fixed topology. Always returns [`FemError::CutUnsupported`], which says why.
    pub fn cut(&mut self, _tets: &[TetId]) -> Result<(), FemError> {
        Err(FemError::CutUnsupported)
    }
}

/// Consistent nodal forces (newtons) of a uniform pressure (pascals, positive pushing into the block)
/// on a face of the block: each triangle of the face gives a third of its load to each corner.
pub fn pressure_loads(
    mesh: &TetMesh,
    face: Face,
    pressure: f64,
) -> Result<Vec<(NodeId, [f64; 3])>, FemError> {
    finite("pressure", pressure)?;
    let mut acc = vec![[0.0; 3]; mesh.node_count()];
    let p = mesh.positions();
    for tri in mesh.face_triangles(face) {
        let [a, b, c] = tri.map(|n| p[n as usize]);
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        // Outward area vector (half the cross product); pressure pushes against it.
        let area = [
            0.5 * (u[1] * v[2] - u[2] * v[1]),
            0.5 * (u[2] * v[0] - u[0] * v[2]),
            0.5 * (u[0] * v[1] - u[1] * v[0]),
        ];
        for n in tri {
            for k in 0..3 {
                acc[n as usize][k] -= pressure * area[k] / 3.0;
            }
        }
    }
    Ok(acc
        .into_iter()
        .enumerate()
        .filter(|(_, f)| f.iter().any(|&x| x != 0.0))
        .map(|(n, f)| (NodeId(n as u32), f))
        .collect())
}
