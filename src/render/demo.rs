//! A synthetic two-layer snapshot (no simulation needed), shared by the headless tests, the render bench
//! and smoke runs: two sheets 4 mm apart over an 8 cm square in the XZ plane, the upper one dura-tan and
//! the lower one pink, with connective fibres between them and forceps above.

use std::f32::consts::PI;

use crate::snapshot::{
    InstrumentKind, InstrumentPose, LayerMesh, RegionKind, RegionShape, Snapshot, SurfacePattern,
    SurfaceRegion,
};

/// Side of the square the sheets cover, metres.
pub const EXTENT: f32 = 0.08;
/// Height of the upper sheet's rim (the lower sheet's rim is at minus this), metres.
pub const HALF_GAP: f32 = 0.002;
/// Height of the gentle dome both sheets follow, metres.
pub const DOME: f32 = 0.0015;

/// Height of a sheet at `(x, z)`: `sign` +1 for the upper sheet, −1 for the lower.
pub fn sheet_height(x: f32, z: f32, sign: f32) -> f32 {
    sign * HALF_GAP + DOME * (PI * x / EXTENT).cos() * (PI * z / EXTENT).cos()
}

fn sheet(name: &str, color: [f32; 4], nu: u32, nv: u32, sign: f32) -> LayerMesh {
    let mut layer = LayerMesh {
        name: name.into(),
        color,
        uv_size: [EXTENT, EXTENT],
        thickness: if sign > 0.0 { 0.0006 } else { 0.0003 },
        pattern: if sign > 0.0 { SurfacePattern::Grain } else { SurfacePattern::Vessels },
        grid: Some([nu, nv]),
        ..Default::default()
    };
    for j in 0..nv {
        for i in 0..nu {
            let x = EXTENT * (i as f32 / (nu - 1) as f32 - 0.5);
            let z = EXTENT * (j as f32 / (nv - 1) as f32 - 0.5);
            layer.positions.push([x, sheet_height(x, z, sign), z]);
            layer.uv.push([i as f32 / (nu - 1) as f32, j as f32 / (nv - 1) as f32]);
            // Gradient of the dome gives the normal; it points away from the other sheet.
            let dx = -DOME * PI / EXTENT * (PI * x / EXTENT).sin() * (PI * z / EXTENT).cos();
            let dz = -DOME * PI / EXTENT * (PI * x / EXTENT).cos() * (PI * z / EXTENT).sin();
            let n = glam::Vec3::new(-dx, 1.0, -dz).normalize() * sign;
            layer.normals.push(n.to_array());
        }
    }
    for j in 0..nv - 1 {
        for i in 0..nu - 1 {
            let a = j * nu + i;
            let b = a + 1;
            let c = a + nu;
            let d = c + 1;
            layer.triangles.push([a, c, b]);
            layer.triangles.push([b, c, d]);
        }
    }
    layer
}

/// Two `nu` × `nv` sheets, a fibre at every `fibre_step`-th vertex in both directions (see [`connect`]),
/// forceps (open) above the front right quarter, a target region over the middle and a forbidden strip
/// along the far edge. `nu` and `nv` are at least 2.
pub fn two_layers(nu: u32, nv: u32, fibre_step: u32) -> Snapshot {
    let (nu, nv, step) = (nu.max(2), nv.max(2), fibre_step.max(1) as usize);
    let upper = sheet("dura", [0.62, 0.45, 0.30, 1.0], nu, nv, 1.0);
    let lower = sheet("arachnoid", [0.78, 0.27, 0.30, 1.0], nu, nv, -1.0);
    let mut snapshot = Snapshot {
        step: 0,
        layers: vec![upper, lower],
        fibres: Vec::new(),
        instrument: Some(InstrumentPose {
            kind: InstrumentKind::Forceps,
            tip: [0.018, 0.01, 0.012],
            axis: glam::Vec3::new(0.45, 0.75, 0.5).normalize().to_array(),
            roll: 0.6,
            closed: false,
        }),
        regions: vec![
            SurfaceRegion {
                kind: RegionKind::Target,
                shape: RegionShape::Rect { u: [0.3, 0.7], v: [0.3, 0.7] },
            },
            SurfaceRegion {
                kind: RegionKind::Forbidden,
                shape: RegionShape::Rect { u: [0.0, 1.0], v: [0.88, 1.0] },
            },
        ],
        fibre_tear_stretch: 4.0,
        ..Snapshot::default()
    };
    connect(&mut snapshot, nu, nv, step);
    snapshot
}

/// Rebuilds `snapshot.fibres`: one fibre from the lower sheet (layer 1) to the upper sheet (layer 0) at
/// every `step`-th vertex of an `nu` × `nv` grid, border included, using the layers' current positions,
/// each standing at its vertex's rest site (the renderer draws those on its fibre lattice, as it does a
/// simulated tissue's).
pub fn connect(snapshot: &mut Snapshot, nu: u32, nv: u32, step: usize) {
    snapshot.fibres.clear();
    snapshot.fibre_stretch.clear();
    snapshot.fibre_sites.clear();
    let [upper, lower, ..] = snapshot.layers.as_slice() else { return };
    for j in (0..nv as usize).step_by(step.max(1)) {
        for i in (0..nu as usize).step_by(step.max(1)) {
            let k = j * nu as usize + i;
            let (Some(&top), Some(&bottom)) = (upper.positions.get(k), lower.positions.get(k)) else {
                continue;
            };
            snapshot.fibres.push([bottom, top]);
            snapshot.fibre_stretch.push(1.0);
            let (du, dv) = (EXTENT / (nu - 1).max(1) as f32, EXTENT / (nv - 1).max(1) as f32);
            snapshot.fibre_sites.push([i as f32 * du, j as f32 * dv, du, dv]);
        }
    }
}
