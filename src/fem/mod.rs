//! A linear elastic finite-element reference model on tetrahedra, after Bro-Nielsen and Cotin
//! ("Real-time volumetric deformable models for surgery simulation using finite elements and
//! condensation", 1996), to measure how far ChainMail with relaxation is from linear elasticity.
//!
//! Owns: the tetrahedral block mesh ([`TetMesh`]), the isotropic material ([`ElasticMaterial`]), element
//! stiffness (`Ke = V · Bᵀ D B`), sparse assembly, the condensation onto the free surface nodes with
//! the explicit inverse computed once at load time ([`FemModel`]), the static mode by selective
//! matrix-vector multiplication, imposed displacements for grasping, the dynamic mode ([`DynamicModel`])
//! and the comparison with ChainMail ([`compare()`]). Factorisations come from `faer` (sparse and
//! dense Cholesky, in place over a kept scratch for imposed sets) and `nalgebra` (element blocks); no solver
//! is written here.
//!
//! Must not import wgpu, winit or egui. Depends on [`chainmail`](crate::chainmail) only for the
//! comparison. Computes in `f64`; units are metres, newtons, pascals, kilograms and seconds, Y up.
//!
//! The model has a fixed topology: [`FemModel::cut`] refuses with [`FemError::CutUnsupported`].

#![warn(missing_docs)]

pub mod compare;
mod dynamic;
pub mod element;
mod error;
mod material;
mod mesh;
mod model;

pub use compare::{CompareConfig, CompareReport, CompareRow, compare};
pub use dynamic::{DynamicModel, DynamicParams};
pub use error::FemError;
pub use material::ElasticMaterial;
pub use mesh::{Face, MAX_NODES, NodeId, Split, TetId, TetMesh};
pub use model::{Base, DEFAULT_MEMORY_LIMIT, FemModel, ImposeWork, LoadOptions, Supports, pressure_loads};
