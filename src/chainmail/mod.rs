//! The ChainMail engine: Gibson's 3D ChainMail with elastic relaxation, in the relative form of Li,
//! Brodlie and Phillips so that it runs on non-uniform, wrapped and curvilinear lattices.
//!
//! Owns: [`Lattice`] (elements, links, rest shape), [`Body`] (current positions, pins, materials,
//! broken links), the chain reaction ([`Body::deform`]) and relaxation ([`Body::relax`]), with their
//! scratch in a [`Workspace`]. Must not import anything graphical (wgpu, winit, egui) nor any other
//! dissect module: everything else builds on this.
//!
//! ## Naming
//! An *element* is a point of the lattice, a *link* joins two elements. A link's constraint is a box
//! on the offset `p[b] - p[a]` between its ends, in lattice coordinates; a link along axis `k` with
//! rest length `D` allows `MinRelCompress·D ..= MaxRelStretch·D` along `k` and `±MaxRelShear·D` across
//! it. The chain reaction moves an element the minimum distance back into the box of its *sponsor*
//! (the neighbour whose move made it a candidate); every element moves at most once per deformation.
//!
//! ## Generic over topology
//! Links are an explicit list with a compressed adjacency, so the same chain reaction and relaxation run
//! on grids (built here), wrapped grids (cylinders, spheres) and, later, triangle and tetrahedral meshes.
//! The chain reaction keeps one candidate list per adjacency slot (Gibson's per-direction lists), so on
//! grids it walks memory row by row.
//!
//! ## Grid fast paths
//! Grids keep a stencil (`stencil.rs`) beside the generic rows. Interior elements find their
//! chain-reaction neighbours by offset, with the generic path's result bit for bit. Whole-body
//! relaxation sweeps work in place, in bands of rows or layers on the thread pool, and relax runs of
//! regular elements a SIMD vector at a time; they agree with the generic path to the rounding of the
//! coordinates (regular elements take a uniform grid's rest offsets as cancelling). Both are checked
//! against the generic path in `tests/chainmail_reference.rs`; anything irregular (borders, seams,
//! cuts, pins, other materials) takes the generic path. The SIMD level is the CPU's widest unless
//! `DISSECT_SIMD` (`avx2`, `scalar`) caps it or [`Workspace::set_simd`] does ([`SimdLevel`]).
//!
//! ## Files, by dependency
//! Each file imports only files above it (and `ids`, `error`, `coords`, `simd`, `schedule`, the
//! leaves):
//!
//! | file | owns |
//! |---|---|
//! | `ids`, `error`, `material`, `coords` | typed ids, errors, materials, coordinate arithmetic and the one scalar clamp |
//! | `simd`, `schedule` | the SIMD level and its dispatch; running two halves of a sweep, or pieces of a scan in turn, on two threads |
//! | `lattice` | elements, links, rest shape, adjacency (immutable) |
//! | `body` | positions, pins, materials, broken links, the slot classes both loops read |
//! | `pairs` | normal pairs: element pairs without a link whose normal offset is bounded (a grid cell's diagonals), so that the slope limit is round |
//! | `stencil` | what the fast paths know of a grid body: neighbour offsets, regular elements, row boxes |
//! | `workspace` | the loops' scratch, the stencil of the body it serves, the SIMD level |
//! | `reaction/` | the chain reaction: API and one-by-one loop (`mod`), shared arrays and checks (`arrays`), runs across rows (`runs`) in portable (`chunk`) or AVX-512 (`avx512`) chunks |
//! | `cone` | a lift's cone: the least distances along the normal from held elements over the bounds, and the lift of the forceps' jaws by it (`docs/implicit-lift.md`); the same cone the other way up for the probe's press, and the press's plain reference |
//! | `relax/` | relaxation: API and generic sweeps (`mod`), the plain kernel (`kernel`), the grid SIMD kernel (`grid`), the split into bands (`bands`) |

mod body;
mod cone;
mod coords;
mod error;
mod ids;
mod lattice;
mod material;
mod pairs;
mod reaction;
mod relax;
pub(crate) mod schedule;
mod simd;
mod stencil;
mod workspace;

pub(crate) use body::INTACT;
pub(crate) use body::fresh_number;
pub use body::{Body, BreakReason};
pub(crate) use cone::Press;
pub use cone::{Cone, ConeLift, distances_plain, press_plain};
pub use error::ChainMailError;
pub use ids::{ElementId, LinkId, MaterialId};
pub(crate) use lattice::SIDE_B as SIDE_B_BIT;
pub use lattice::{Axis, BYTES_PER_ELEMENT, GridSpec, Lattice, LinkSpec, MAX_ELEMENTS};
pub use material::{DEFAULT_THICKNESS, DEFAULT_TOUGHNESS, DEFAULT_YOUNG_MODULUS, Limits, Material};
pub use pairs::NormalPair;
pub(crate) use reaction::has_bit;
pub use reaction::{Deformation, Pass};
pub(crate) use relax::sweeps_within;
pub use relax::{Coarse, RelaxBudget, RelaxRegion, RelaxReport};
pub use schedule::worker_pool;
pub(crate) use simd::Prefetch;
pub use simd::{SIMD_ENV, SimdLevel};
pub use workspace::Workspace;
pub(crate) use workspace::touched;
