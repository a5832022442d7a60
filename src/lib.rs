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
//! | [`chainmail`] | lattices, materials, the chain reaction, relaxation, broken links, grid fast paths | std, serde, thiserror, pulp, rayon, log |
//! | [`surface`] | parametric surfaces X(u, v) and the (u, v, h) mapping | chainmail |
//! | [`tissue`] | layers, connective fibres, pins, grasp and push, contact, cuts, tears, meshes | chainmail, surface |
//! | [`fem`] | the linear elastic tetrahedral reference model (condensation, SMVM) and its comparison with ChainMail | std, serde, thiserror, faer, nalgebra, chainmail |
//! | [`simulation`] | the world, the fixed-step clock, the snapshot the renderer reads | chainmail and the modules below it |
//! | [`scene`] | RON scenes and scripts: schema, loading, validation, errors at `path:line:column`; builds a world | chainmail, surface, tissue, simulation, serde, ron |
//! | [`instrument`] | probe, forceps, scalpel: commands, pose, picking with parry3d | chainmail, tissue, simulation (types) |
//! | [`runner`] | the script player, run metrics and final state (headless runs) | scene, simulation, training |
//! | [`training`] | exercise goals, live assessment and score, session report and plot | tissue, simulation |
//! | [`render`] | wgpu device, scene pipelines and buffers, orbit camera and picking rays, headless PNG capture | wgpu, glam, bytemuck, image, `simulation` (snapshot types only); never winit or egui |
//! | [`ui`] | the egui panels, one type per panel (`View`), and the actions they ask for | egui, `World`'s public API, scene, training (types); never winit or wgpu |
//! | `web` (wasm32 only) | the trainer in a browser: one canvas with both views, scenes from the page, downloads | winit (web), egui-winit, egui-wgpu, ui, render, `app`'s input logic, wasm-bindgen, web-sys |
//! | [`app`] | the two windows, the event loop, input to instrument commands, recording and replay, hot reload | winit (only here), egui-winit, egui-wgpu, ui, render, and the simulation side's public API |
//!
//! The simulation side (`chainmail`, `surface`, `tissue`, `instrument`, `simulation`, `scene`,
//! `training`, `fem`) never imports wgpu, winit or egui.

#[cfg(not(target_arch = "wasm32"))]
pub mod app;
pub mod chainmail;
pub mod fem;
pub mod instrument;
pub mod render;
pub mod runner;
pub mod scene;
pub mod simulation;
pub mod snapshot;
pub mod surface;
pub mod tissue;
pub mod training;
pub mod ui;
#[cfg(target_arch = "wasm32")]
pub mod web;
