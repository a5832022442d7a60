//! Mouse and keyboard: camera control for every 3D view, and the trainee's hand (picking with the
//! cursor's ray, grasping, pulling, cutting, pushing) turned into instrument [`Command`]s.
//!
//! Pure input logic on glam vectors and small enums; the winit events are translated in `mod.rs`.

use glam::{Vec2, Vec3};

use crate::instrument::{Hit, PROBE_RADIUS};
use crate::render::OrbitCamera;
use crate::simulation::{Command, InstrumentKind, Snapshot, WorldView};
use crate::tissue::CutDepth;
use crate::ui::ToolState;

/// Radians of orbit per pixel of drag.
const ORBIT_PER_PX: f32 = 0.008;
/// Zoom factor per wheel notch.
const ZOOM_PER_NOTCH: f32 = 0.9;
/// Insert depth change per wheel notch, millimetres.
const INSERT_PER_NOTCH_MM: f32 = 1.0;
/// Where a hovering tip waits above the surface, metres.
const HOVER_GAP: f32 = 0.002;

/// The view shape a scene's camera is framed for (width over height); narrower views back off a little
/// (at most [`MAX_BACK_OFF`]), keeping the work area in the middle of the tissue in view and the tissue
/// filling most of the view, rather than fitting the whole tissue into a narrow view.
const FRAMED_ASPECT: f32 = 1.5;
/// The most a narrow view backs the camera off, as a factor on its distance.
const MAX_BACK_OFF: f32 = 1.25;

/// A camera that can be put back where it started.
#[derive(Clone, Copy, Debug)]
pub struct CameraRig {
    /// The camera now.
    pub camera: OrbitCamera,
    /// Where [`CameraRig::reset`] puts it (before fitting to the view's shape).
    pub home: OrbitCamera,
    /// The user moved the camera: the view's shape no longer refits it.
    pub moved: bool,
    aspect: f32,
}

impl CameraRig {
    /// A rig starting (and resetting) at `camera`.
    pub fn new(camera: OrbitCamera) -> Self {
        Self { camera, home: camera, moved: false, aspect: FRAMED_ASPECT }
    }

    /// Back to the home view, fitted to the view's shape.
    pub fn reset(&mut self) {
        self.moved = false;
        self.fit(self.aspect);
    }

    /// The view's shape changed: an untouched camera backs off so a narrow view still shows the
    /// tissue's width.
    pub fn fit(&mut self, aspect: f32) {
        if !(aspect.is_finite() && aspect > 0.0) {
            return;
        }
        self.aspect = aspect;
        if !self.moved {
            self.camera = self.home;
            self.camera.distance *= (FRAMED_ASPECT / aspect).sqrt().clamp(1.0, MAX_BACK_OFF);
        }
    }
}

/// Which mouse buttons are down and where the cursor is, in one 3D view.
#[derive(Clone, Copy, Debug, Default)]
pub struct Pointer {
    /// Cursor, physical pixels relative to the view's corner.
    pub pos: Vec2,
    /// Size of the view, physical pixels.
    pub size: Vec2,
    /// Left button down (started in this view).
    pub left: bool,
    /// Right button down.
    pub right: bool,
    /// Middle button down.
    pub middle: bool,
}

/// Moves a camera for a drag of `delta` pixels: right button orbits, middle (or shift with right) pans.
pub fn drag_camera(rig: &mut CameraRig, p: &Pointer, shift: bool, delta: Vec2) {
    rig.moved = true;
    if p.middle || (p.right && shift) {
        rig.camera.pan(delta, p.size.y);
    } else if p.right {
        rig.camera.orbit(-delta.x * ORBIT_PER_PX, delta.y * ORBIT_PER_PX);
    }
}

/// Zooms a camera by wheel notches (positive: closer).
pub fn zoom_camera(rig: &mut CameraRig, notches: f32) {
    rig.moved = true;
    rig.camera.zoom(ZOOM_PER_NOTCH.powf(notches));
}

/// What the left button is doing with the instrument.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Stroke {
    /// Forceps hold tissue; the tip follows the cursor on the plane through `point` facing `normal`.
    Pull { point: Vec3, normal: Vec3 },
    /// The scalpel cuts along the surface under the cursor.
    Cut,
    /// The probe pushes; its tip follows the cursor on a plane like the forceps'.
    Push { point: Vec3, normal: Vec3 },
}

/// The trainee's hand: the tool settings and the stroke in progress.
#[derive(Clone, Debug, Default)]
pub struct Hand {
    /// Instrument, depth, roll, tilt, insert.
    pub tool: ToolState,
    stroke: Option<Stroke>,
}

/// A ray's meeting with a plane.
fn on_plane(origin: Vec3, dir: Vec3, point: Vec3, normal: Vec3) -> Option<Vec3> {
    let d = dir.dot(normal);
    if d.abs() < 1e-6 {
        return None;
    }
    let t = (point - origin).dot(normal) / d;
    (t > 0.0).then(|| origin + t * dir)
}

impl Hand {
    /// Whether the left button is using the instrument.
    pub fn busy(&self) -> bool {
        self.stroke.is_some()
    }

    /// Takes another instrument: ends the stroke in progress (the world keeps a forceps grasp).
    pub fn select(&mut self, kind: InstrumentKind, out: &mut Vec<Command>) {
        self.end_stroke(false, out);
        self.tool.kind = kind;
        out.push(Command::Select(kind));
    }

    /// Sets the scalpel's depth (takes effect at the next cut).
    pub fn set_depth(&mut self, depth: CutDepth, out: &mut Vec<Command>) {
        self.tool.depth = depth;
        out.push(Command::SetDepth(depth));
    }

    /// The axis for the current tilt, leaning towards the viewer of `camera`.
    pub fn axis(&self, camera: &OrbitCamera) -> [f32; 3] {
        let (forward, _, _) = camera.basis();
        let back = Vec3::new(-forward.x, 0.0, -forward.z).normalize_or(Vec3::Z);
        let t = self.tool.tilt_deg.to_radians();
        (t.cos() * Vec3::Y + t.sin() * back).to_array()
    }

    /// The left button went down with the cursor's ray `(origin, dir)` meeting the tissue at `hit`.
    /// Returns the pick the forceps close on: the caller turns it into the element under it with the
    /// world it has (`World::element_at`), before the commands pushed to `out`.
    pub fn press(
        &mut self,
        world: &WorldView,
        camera: &OrbitCamera,
        ray: (Vec3, Vec3),
        hit: Option<Hit>,
        out: &mut Vec<Command>,
    ) -> Option<Hit> {
        let (forward, _, _) = camera.basis();
        match self.tool.kind {
            InstrumentKind::Forceps => {
                if let Some(held) = world.grasped_position() {
                    // The forceps were left clamped: take them up where they are.
                    self.stroke = Some(Stroke::Pull { point: Vec3::from(held), normal: forward });
                    self.tool.insert_mm = 0.0;
                    return None;
                }
                let hit = hit?;
                self.tool.insert_mm = 0.0;
                self.stroke = Some(Stroke::Pull { point: Vec3::from(hit.point), normal: forward });
                return Some(hit);
            }
            InstrumentKind::Scalpel => {
                let hit = hit?;
                out.push(Command::SetDepth(self.tool.depth));
                out.push(Command::MoveTo(hit.point));
                out.push(Command::BeginCut);
                self.stroke = Some(Stroke::Cut);
            }
            InstrumentKind::Probe => {
                let hit = hit?;
                self.stroke = Some(Stroke::Push { point: Vec3::from(hit.point), normal: forward });
                out.push(Command::MoveTo(self.probe_tip(Vec3::from(hit.point), ray.1)));
            }
        }
        None
    }

    fn probe_tip(&self, surface: Vec3, dir: Vec3) -> [f32; 3] {
        // The ball's centre sits on the surface plus the push depth: it pushes by its radius at once.
        (surface + dir * (self.tool.insert_mm * 1e-3)).to_array()
    }

    /// The cursor moved (or the insert depth changed) with the left button down, or hovering.
    pub fn drag(&mut self, world: &WorldView, ray: (Vec3, Vec3), hit: Option<Hit>, out: &mut Vec<Command>) {
        let (origin, dir) = ray;
        match self.stroke {
            Some(Stroke::Pull { point, normal }) => {
                if let Some(p) = on_plane(origin, dir, point, normal) {
                    out.push(Command::MoveTo((p + normal * (self.tool.insert_mm * 1e-3)).to_array()));
                }
            }
            Some(Stroke::Cut) => {
                if let Some(hit) = hit {
                    out.push(Command::MoveTo(hit.point));
                }
            }
            Some(Stroke::Push { point, normal }) => {
                if let Some(p) = on_plane(origin, dir, point, normal) {
                    out.push(Command::MoveTo(self.probe_tip(p, dir)));
                }
            }
            None => {
                // Hovering: the tip waits just above the surface under the cursor. Forceps holding
                // tissue stay where they are (moving them would pull).
                let inst = world.instrument();
                if inst.kind == InstrumentKind::Forceps && inst.grasped.is_some() {
                    return;
                }
                let Some(hit) = hit else { return };
                let gap = if self.tool.kind == InstrumentKind::Probe {
                    PROBE_RADIUS + HOVER_GAP
                } else {
                    HOVER_GAP
                };
                out.push(Command::MoveTo((Vec3::from(hit.point) - dir * gap).to_array()));
            }
        }
    }

    /// Whether the next [`Hand::drag`] reads the tissue under the cursor: a cut follows the surface and
    /// a hover puts the tip above it; a pull or a push follows its plane and forceps left clamped stay
    /// where they are, so the picker need not be rebuilt for them (at 128 x 96 that is two meshes of
    /// 24 576 triangles every frame of a lift).
    pub fn reads_tissue(&self, world: &WorldView) -> bool {
        match self.stroke {
            Some(Stroke::Pull { .. } | Stroke::Push { .. }) => false,
            Some(Stroke::Cut) => true,
            None => {
                let inst = world.instrument();
                !(inst.kind == InstrumentKind::Forceps && inst.grasped.is_some())
            }
        }
    }

    /// The wheel turned while the left button is held: insert (forceps) or push deeper (probe).
    /// Returns false when no stroke takes the wheel (the camera zooms instead).
    pub fn wheel(&mut self, notches: f32) -> bool {
        match self.stroke {
            Some(Stroke::Pull { .. } | Stroke::Push { .. }) => {
                self.tool.insert_mm =
                    (self.tool.insert_mm - notches * INSERT_PER_NOTCH_MM).clamp(-20.0, 20.0);
                true
            }
            _ => false,
        }
    }

    /// The left button went up. With `keep_clamped`, forceps stay closed on the tissue.
    pub fn release(&mut self, keep_clamped: bool, out: &mut Vec<Command>) {
        self.end_stroke(keep_clamped, out);
    }

    fn end_stroke(&mut self, keep_clamped: bool, out: &mut Vec<Command>) {
        match self.stroke.take() {
            Some(Stroke::Pull { .. }) if !keep_clamped => out.push(Command::Release),
            Some(Stroke::Cut) => out.push(Command::EndCut),
            _ => {}
        }
    }
}

/// Casts the cursor's ray against the snapshot's tissue.
pub fn pick(
    picker: &crate::instrument::Picker,
    snapshot: &Snapshot,
    camera: &OrbitCamera,
    pointer: &Pointer,
) -> ((Vec3, Vec3), Option<Hit>) {
    let ray = camera.ray(pointer.pos, pointer.size);
    let hit = picker.cast(snapshot, ray.0.to_array(), ray.1.to_array());
    (ray, hit)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ray_meets_a_plane_in_front_only() {
        let p = on_plane(Vec3::new(0.0, 1.0, 0.0), Vec3::NEG_Y, Vec3::ZERO, Vec3::Y);
        assert_eq!(p, Some(Vec3::ZERO));
        assert_eq!(on_plane(Vec3::new(0.0, 1.0, 0.0), Vec3::Y, Vec3::ZERO, Vec3::Y), None);
        assert_eq!(on_plane(Vec3::ZERO, Vec3::X, Vec3::ZERO, Vec3::Y), None);
    }

    #[test]
    fn only_cuts_and_hovers_read_the_tissue_under_the_cursor() {
        let world = WorldView::default();
        let mut hand = Hand::default();
        assert!(hand.reads_tissue(&world), "a hover puts the tip above the tissue");
        hand.stroke = Some(Stroke::Cut);
        assert!(hand.reads_tissue(&world));
        hand.stroke = Some(Stroke::Pull { point: Vec3::ZERO, normal: Vec3::NEG_Z });
        assert!(!hand.reads_tissue(&world), "a pull follows its plane");
        hand.stroke = Some(Stroke::Push { point: Vec3::ZERO, normal: Vec3::NEG_Z });
        assert!(!hand.reads_tissue(&world));
    }

    #[test]
    fn the_wheel_inserts_only_during_a_pull_or_push() {
        let mut hand = Hand::default();
        assert!(!hand.wheel(1.0));
        hand.stroke = Some(Stroke::Pull { point: Vec3::ZERO, normal: Vec3::NEG_Z });
        assert!(hand.wheel(2.0));
        assert_eq!(hand.tool.insert_mm, -2.0);
        let mut out = vec![];
        hand.release(false, &mut out);
        assert_eq!(out, vec![Command::Release]);
    }
}
