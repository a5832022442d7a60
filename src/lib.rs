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
//! Dependencies point one way: `app → ui, render → runner → scene, training → simulation → instrument →
//! tissue → chainmail, surface, fem`, and everything may import the leaf [`snapshot`]. No module imports
//! one above it; `ARCHITECTURE.md` at the top of the repository says more, with a step's data flow.
//!
//! | module | owns | may import |
//! |---|---|---|
//! | [`chainmail`] | lattices, materials, the chain reaction, relaxation, broken links, grid fast paths | std, serde, thiserror, pulp, rayon, log |
//! | [`surface`] | parametric surfaces X(u, v) and the (u, v, h) mapping | chainmail |
//! | [`snapshot`] | the shared vocabulary: the snapshot the renderer reads, layer meshes, instrument kind and pose, camera spec | serde only (a leaf) |
//! | [`fem`] | the linear elastic tetrahedral reference model (condensation, SMVM) and its comparison with ChainMail | std, serde, thiserror, faer, nalgebra, chainmail |
//! | [`tissue`] | layers, connective fibres, pins, grasp and push, contact, cuts, tears, meshes; its deformation model (ChainMail or FEM) | chainmail, surface, fem, snapshot, rayon (a large region's tear scan on two threads) |
//! | [`instrument`] | probe, forceps, scalpel: state, pose, picking with parry3d | chainmail, tissue, snapshot |
//! | [`simulation`] | the world: its clock and step length, its commands, the ordered phases of a step, the snapshot it fills | chainmail, tissue, instrument, snapshot, web-time |
//! | [`haptics`] | haptic devices (mouse, simulated, Haply Inverse3 behind the `haply` feature), the virtual coupling and its passivity controller | instrument, snapshot, web-time; `haply` and `tokio` with the feature |
//! | [`training`] | exercise goals, live assessment and score, session report and plot | tissue, simulation |
//! | [`scene`] | RON scenes, scripts and recordings: schema, loading, validation, errors at `path:line:column`; builds a world | chainmail, surface, tissue, instrument, simulation, training (goals), serde, ron |
//! | [`runner`] | the [`runner::Episode`] every driver steps (world, assessor, recorder, command source), the script player, run metrics and final state; natively, the simulation thread that steps an episode at its deadlines (`runner::SimThread`) | scene, simulation, training, haptics and below; crossbeam-channel, triple_buffer, spin_sleep |
//! | [`render`] | wgpu device, scene pipelines and buffers, orbit camera and picking rays, headless PNG capture | wgpu, glam, bytemuck, image, `snapshot`; never winit or egui |
//! | [`ui`] | the egui panels, one type per panel (`View`), and the actions they ask for | egui, `WorldView` (a copy of the world's figures), scene, training (types); never winit or wgpu |
//! | `web` (wasm32 only) | the trainer in a browser: one canvas with both views, scenes from the page, downloads | winit (web), egui-winit, egui-wgpu, ui, render, `app`'s input logic, wasm-bindgen, web-sys |
//! | [`app`] | the two windows, the event loop, input to instrument commands, the session (an episode, recording and replay, hot reload) | winit (only here), egui-winit, egui-wgpu, ui, render, and the simulation side's public API (`World`, `Episode`) |
//!
//! The simulation side (`snapshot`, `chainmail`, `surface`, `tissue`, `instrument`, `simulation`,
//! `scene`, `training`, `runner`, `fem`, `haptics`) never imports wgpu, winit or egui.

#[cfg(not(target_arch = "wasm32"))]
pub mod app;
pub mod chainmail;
pub mod fem;
pub mod haptics;
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

/// The native builds' allocator: mimalloc. It backs the tissue's large per-element arrays (positions,
/// stamps, slot rows: megabytes each at 512 × 384) with transparent huge pages, which Linux gives by
/// default only to memory that asks for them (`madvise`) and glibc's allocator does not ask. With 4 KiB
/// pages a lifting step that reads tens of thousands of elements across a dozen arrays keeps missing the
/// address translation cache. On the 2-vCPU Intel machine of 2026-11-29 (three alternating runs of the
/// careful meninges exercise each, AVX2) the mean step fell by 10 % at 256 × 192 and 20 % at 512 × 384,
/// the p99 by 15 % and 23 %; the peak memory of `dissect run` rose from 255 to 310 MB and from 508 to
/// 610 MB. The arrays the steps write are written once when a body is built (`chainmail::touched`):
/// otherwise the first step to reach a huge page stops to have it zeroed and mapped (4 to 22 ms in the
/// first steps at 512 × 384). Declared here, so that every binary, test and bench that links the library
/// allocates the same way. (The browser build keeps Rust's, and so does the `count-allocations` feature,
/// under which the test that counts a step's allocations installs its counting allocator.)
#[cfg(not(any(target_arch = "wasm32", feature = "count-allocations")))]
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;
