//! Procedural instrument geometry, built once on the CPU: no GPU types here.
//!
//! Instruments are modelled in a local frame with the tip at the origin and the shaft along +Z (towards
//! the handle); [`instrument_parts`] gives each part's model matrix for a pose. Lengths are metres.

use glam::{Mat4, Quat, Vec3};

use crate::snapshot::{InstrumentKind, InstrumentPose};

/// An indexed triangle mesh with per-vertex normals. Normal orientation does not matter for drawing
/// (the shader turns normals towards the viewer), only their direction.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals, one per position.
    pub normals: Vec<[f32; 3]>,
    /// Triangles, three indices each.
    pub indices: Vec<u32>,
}

impl MeshData {
    fn vertex(&mut self, p: Vec3, n: Vec3) -> u32 {
        let i = self.positions.len() as u32;
        self.positions.push(p.to_array());
        self.normals.push(n.normalize_or(Vec3::Y).to_array());
        i
    }

    /// A flat quad (corners in order around it).
    fn quad(&mut self, c: [Vec3; 4]) {
        let n = (c[1] - c[0]).cross(c[3] - c[0]);
        let i: Vec<u32> = c.iter().map(|&p| self.vertex(p, n)).collect();
        self.indices.extend_from_slice(&[i[0], i[1], i[2], i[0], i[2], i[3]]);
    }

    /// Appends another mesh.
    pub fn append(&mut self, other: &MeshData) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.indices.extend(other.indices.iter().map(|i| i + base));
    }

    /// A UV sphere.
    pub fn sphere(center: Vec3, radius: f32, rings: u32, sectors: u32) -> Self {
        let mut m = Self::default();
        let rings = rings.max(2);
        let sectors = sectors.max(3);
        for r in 0..=rings {
            let theta = std::f32::consts::PI * r as f32 / rings as f32;
            for s in 0..=sectors {
                let phi = std::f32::consts::TAU * s as f32 / sectors as f32;
                let n = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
                m.vertex(center + radius * n, n);
            }
        }
        let row = sectors + 1;
        for r in 0..rings {
            for s in 0..sectors {
                let a = r * row + s;
                let b = a + row;
                m.indices.extend_from_slice(&[a, b, a + 1, a + 1, b, b + 1]);
            }
        }
        m
    }

    /// A capped, possibly tapered, cylinder along Z from `z0` (radius `r0`) to `z1` (radius `r1`).
    pub fn cylinder_z(z0: f32, r0: f32, z1: f32, r1: f32, sectors: u32) -> Self {
        let mut m = Self::default();
        let sectors = sectors.max(3);
        for s in 0..=sectors {
            let phi = std::f32::consts::TAU * s as f32 / sectors as f32;
            let radial = Vec3::new(phi.cos(), phi.sin(), 0.0);
            m.vertex(Vec3::new(radial.x * r0, radial.y * r0, z0), radial);
            m.vertex(Vec3::new(radial.x * r1, radial.y * r1, z1), radial);
        }
        for s in 0..sectors {
            let a = 2 * s;
            m.indices.extend_from_slice(&[a, a + 2, a + 1, a + 1, a + 2, a + 3]);
        }
        for (z, r) in [(z0, r0), (z1, r1)] {
            let n = Vec3::Z;
            let c = m.vertex(Vec3::new(0.0, 0.0, z), n);
            let first = m.positions.len() as u32;
            for s in 0..=sectors {
                let phi = std::f32::consts::TAU * s as f32 / sectors as f32;
                m.vertex(Vec3::new(phi.cos() * r, phi.sin() * r, z), n);
            }
            for s in 0..sectors {
                m.indices.extend_from_slice(&[c, first + s, first + s + 1]);
            }
        }
        m
    }

    /// A box along Z whose cross-section is `[-hw, hw] × [y0, y0 + 2 hh]`, tapering linearly from
    /// (`hw0`, `hh0`) at `z0` to (`hw1`, `hh1`) at `z1`. Flat faces.
    pub fn tapered_box_z(z0: f32, hw0: f32, hh0: f32, z1: f32, hw1: f32, hh1: f32, y0: f32) -> Self {
        let corners = |z: f32, hw: f32, hh: f32| {
            [
                Vec3::new(-hw, y0, z),
                Vec3::new(hw, y0, z),
                Vec3::new(hw, y0 + 2.0 * hh, z),
                Vec3::new(-hw, y0 + 2.0 * hh, z),
            ]
        };
        let a = corners(z0, hw0, hh0);
        let b = corners(z1, hw1, hh1);
        let mut m = Self::default();
        for i in 0..4 {
            let j = (i + 1) % 4;
            m.quad([a[i], a[j], b[j], b[i]]);
        }
        m.quad([a[0], a[1], a[2], a[3]]);
        m.quad([b[3], b[2], b[1], b[0]]);
        m
    }

    /// A bar along Z through rectangular cross-sections `(z, half_width, y_bottom, half_height)`, in
    /// order of `z`, joined by flat quads; both ends capped. Lofts a bent, tapering forceps leaf.
    pub fn loft_z(sections: &[(f32, f32, f32, f32)]) -> Self {
        let corners = |&(z, hw, y0, hh): &(f32, f32, f32, f32)| {
            [
                Vec3::new(-hw, y0, z),
                Vec3::new(hw, y0, z),
                Vec3::new(hw, y0 + 2.0 * hh, z),
                Vec3::new(-hw, y0 + 2.0 * hh, z),
            ]
        };
        let mut m = Self::default();
        for w in sections.windows(2) {
            let (a, b) = (corners(&w[0]), corners(&w[1]));
            for i in 0..4 {
                let j = (i + 1) % 4;
                m.quad([a[i], a[j], b[j], b[i]]);
            }
        }
        if let (Some(first), Some(last)) = (sections.first(), sections.last()) {
            let (a, b) = (corners(first), corners(last));
            m.quad([a[0], a[1], a[2], a[3]]);
            m.quad([b[3], b[2], b[1], b[0]]);
        }
        m
    }

    /// A convex outline in the local XZ plane (points `(x, z)` in order), extruded to `±half_thickness`
    /// along Y. Flat faces.
    pub fn extrude_y(outline: &[(f32, f32)], half_thickness: f32) -> Self {
        let mut m = Self::default();
        let at = |(x, z): (f32, f32), y: f32| Vec3::new(x, y, z);
        for y in [half_thickness, -half_thickness] {
            let n = Vec3::new(0.0, y.signum(), 0.0);
            let first = m.positions.len() as u32;
            for &p in outline {
                m.vertex(at(p, y), n);
            }
            for k in 1..outline.len().saturating_sub(1) as u32 {
                m.indices.extend_from_slice(&[first, first + k, first + k + 1]);
            }
        }
        for i in 0..outline.len() {
            let p = outline[i];
            let q = outline[(i + 1) % outline.len()];
            m.quad([
                at(p, -half_thickness),
                at(q, -half_thickness),
                at(q, half_thickness),
                at(p, half_thickness),
            ]);
        }
        m
    }
}

/// One rigid piece of an instrument model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Part {
    /// The probe: ball tip, rod and grip.
    Probe,
    /// One forceps jaw (drawn twice, mirrored).
    Jaw,
    /// The scalpel handle.
    ScalpelHandle,
    /// The scalpel's flat blade.
    ScalpelBlade,
}

impl Part {
    /// Every part, in the order the renderer uploads them.
    pub const ALL: [Part; 4] = [Part::Probe, Part::Jaw, Part::ScalpelHandle, Part::ScalpelBlade];
}

/// Forceps leaf length from the tip to where the two leaves join (they flex about it), metres.
pub const JAW_LENGTH: f32 = 0.1;
/// Forceps opening: angle of each leaf off the axis when open, radians.
pub const JAW_OPEN_ANGLE: f32 = 0.025;
const PROBE_BALL: f32 = 0.0015;

/// The local-frame mesh of a part.
pub fn part_mesh(part: Part) -> MeshData {
    match part {
        Part::Probe => {
            let mut m = MeshData::sphere(Vec3::new(0.0, 0.0, PROBE_BALL), PROBE_BALL, 10, 16);
            m.append(&MeshData::cylinder_z(PROBE_BALL, 0.0006, 0.05, 0.0007, 12));
            m.append(&MeshData::cylinder_z(0.05, 0.0022, 0.11, 0.0025, 16));
            m
        }
        Part::Jaw => MeshData::loft_z(&[
            (0.0, 0.0005, 0.0001, 0.0003),
            (0.008, 0.0009, 0.0002, 0.00032),
            (0.03, 0.0019, 0.0009, 0.00035),
            (0.055, 0.0027, 0.0019, 0.00035),
            (0.08, 0.0028, 0.0024, 0.00035),
            (JAW_LENGTH, 0.0026, 0.0005, 0.0006),
        ]),
        Part::ScalpelHandle => {
            let mut m = MeshData::tapered_box_z(0.028, 0.0032, 0.0011, 0.125, 0.0046, 0.0014, -0.0012);
            // A fluted grip: raised bars across the handle.
            for k in 0..7 {
                let z = 0.045 + 0.006 * k as f32;
                m.append(&MeshData::tapered_box_z(z, 0.0038, 0.0013, z + 0.002, 0.0038, 0.0013, -0.0014));
            }
            m
        }
        // A No. 10 blade: a curved cutting belly in front of a straight spine (convex outline).
        Part::ScalpelBlade => MeshData::extrude_y(
            &[
                (0.0, 0.0),
                (0.0015, 0.0015),
                (0.003, 0.004),
                (0.004, 0.008),
                (0.0045, 0.013),
                (0.0043, 0.02),
                (0.0039, 0.026),
                (0.0035, 0.032),
                (-0.0015, 0.032),
                (-0.0015, 0.012),
                (-0.001, 0.005),
                (-0.0005, 0.002),
            ],
            0.00015,
        ),
    }
}

/// Local frame to world: tip at `pose.tip`, local +Z along `pose.axis`, turned by `pose.roll`.
pub fn pose_matrix(pose: &InstrumentPose) -> Mat4 {
    let axis = Vec3::from(pose.axis).normalize_or(Vec3::Y);
    let align = Quat::from_rotation_arc(Vec3::Z, axis);
    Mat4::from_rotation_translation(align * Quat::from_rotation_z(pose.roll), Vec3::from(pose.tip))
}

/// The parts of the instrument at `pose`, each with its model matrix (at most two).
pub fn instrument_parts(pose: &InstrumentPose) -> [Option<(Part, Mat4)>; 2] {
    let base = pose_matrix(pose);
    match pose.kind {
        InstrumentKind::Probe => [Some((Part::Probe, base)), None],
        InstrumentKind::Forceps => {
            let angle = if pose.closed { 0.0 } else { JAW_OPEN_ANGLE };
            let hinge = Vec3::new(0.0, 0.0, JAW_LENGTH);
            let open =
                Mat4::from_translation(hinge) * Mat4::from_rotation_x(angle) * Mat4::from_translation(-hinge);
            [
                Some((Part::Jaw, base * open)),
                Some((Part::Jaw, base * Mat4::from_rotation_z(std::f32::consts::PI) * open)),
            ]
        }
        InstrumentKind::Scalpel => [Some((Part::ScalpelHandle, base)), Some((Part::ScalpelBlade, base))],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meshes_are_consistent() {
        for part in Part::ALL {
            let m = part_mesh(part);
            assert_eq!(m.positions.len(), m.normals.len());
            assert_eq!(m.indices.len() % 3, 0);
            assert!(m.indices.iter().all(|&i| (i as usize) < m.positions.len()), "{part:?}");
        }
    }

    #[test]
    fn pose_puts_tip_and_axis_in_place() {
        let pose = InstrumentPose {
            kind: InstrumentKind::Probe,
            tip: [0.01, 0.02, 0.03],
            axis: [0.0, 1.0, 0.0],
            roll: 0.4,
            closed: false,
        };
        let m = pose_matrix(&pose);
        assert!(m.transform_point3(Vec3::ZERO).distance(Vec3::new(0.01, 0.02, 0.03)) < 1e-6);
        assert!(m.transform_vector3(Vec3::Z).distance(Vec3::Y) < 1e-5);
    }

    #[test]
    fn forceps_jaws_open_and_close() {
        let mut pose = InstrumentPose {
            kind: InstrumentKind::Forceps,
            tip: [0.0; 3],
            axis: [0.0, 0.0, 1.0],
            roll: 0.0,
            closed: false,
        };
        let gap = |pose: &InstrumentPose| {
            let [Some((_, a)), Some((_, b))] = instrument_parts(pose) else { panic!("two jaws") };
            a.transform_point3(Vec3::ZERO).distance(b.transform_point3(Vec3::ZERO))
        };
        let open = gap(&pose);
        pose.closed = true;
        let closed = gap(&pose);
        assert!(open > 0.004 && closed < 1e-4, "open {open}, closed {closed}");
    }
}
