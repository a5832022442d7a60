//! # dissect
//!
//! A soft-tissue cutting trainer: two layers of tissue, joined by connective fibres, are cut apart and
//! pulled away from each other in real time. The deformation is SurfaceChainMail (Li, Brodlie and
//! Phillips) on top of Gibson's 3D ChainMail with elastic relaxation.
//!
//! ## Conventions
//! Units are metres and seconds; axes are right-handed with **Y up**. Lattice coordinates of a surface
//! layer are `(u, v, h)`: the two surface parameters and the offset along the surface normal.
//!
//! ## Architecture map
//! Dependencies point one way: `app → ui, render → simulation → tissue, instrument → chainmail, surface`.
//!
//! | module | owns | may import |
//! |---|---|---|
//! | [`chainmail`] | lattices, materials, the chain reaction, relaxation, broken links | std, serde, thiserror |
//! | [`fem`] | the linear elastic tetrahedral reference model (condensation, SMVM) and its comparison with ChainMail | std, serde, thiserror, faer, nalgebra, chainmail |
//! | [`simulation`] | the world, the fixed-step clock, the snapshot the renderer reads | chainmail and the modules below it |
//!
//! The simulation side (`chainmail`, `surface`, `tissue`, `instrument`, `simulation`, `scene`,
//! `training`, `fem`) never imports wgpu, winit or egui.

pub mod chainmail;
pub mod fem;
pub mod simulation;
