//! An orbit camera around a target point, its matrices (wgpu conventions: depth in `[0, 1]`, Y up) and
//! picking rays. Pure glam: no GPU types, usable by the app's input code and by tests.

use glam::{Mat4, Vec2, Vec3};

use crate::snapshot::CameraSpec;

/// Pitch is kept inside ±89° so the view never flips over the pole.
const MAX_PITCH: f32 = 89.0_f32.to_radians();
/// The closest the eye may come to the target, metres.
const MIN_DISTANCE: f32 = 0.005;
/// The farthest the eye may go from the target, metres.
const MAX_DISTANCE: f32 = 5.0;

/// A camera orbiting `target` at `distance`, looking at it from `yaw` and `pitch`.
///
/// Yaw 0 looks along −Z (the eye on +Z); positive pitch puts the eye above the target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitCamera {
    /// Point looked at and orbited, world space (metres).
    pub target: Vec3,
    /// Eye-to-target distance, metres.
    pub distance: f32,
    /// Angle around the world Y axis, radians.
    pub yaw: f32,
    /// Elevation above the target's horizontal plane, radians.
    pub pitch: f32,
    /// Vertical field of view, degrees.
    pub fov_y_deg: f32,
}

impl OrbitCamera {
    /// The camera a scene describes.
    pub fn from_spec(spec: &CameraSpec) -> Self {
        let target = Vec3::from(spec.target);
        let offset = Vec3::from(spec.eye) - target;
        let distance = offset.length().clamp(MIN_DISTANCE, MAX_DISTANCE);
        let dir = offset.try_normalize().unwrap_or(Vec3::Z);
        let pitch = dir.y.clamp(-1.0, 1.0).asin().clamp(-MAX_PITCH, MAX_PITCH);
        let yaw = dir.x.atan2(dir.z);
        let fov_y_deg = if spec.fov_y_deg.is_finite() { spec.fov_y_deg.clamp(5.0, 120.0) } else { 45.0 };
        Self { target, distance, yaw, pitch, fov_y_deg }
    }

    /// The spec of the current view (for saving a view in a scene).
    pub fn to_spec(&self) -> CameraSpec {
        CameraSpec { eye: self.eye().to_array(), target: self.target.to_array(), fov_y_deg: self.fov_y_deg }
    }

    /// Eye position, world space.
    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + self.distance * Vec3::new(cp * sy, sp, cp * cy)
    }

    /// Unit vectors (forward, right, up) of the view, world space.
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let forward = (self.target - self.eye()).normalize_or(Vec3::NEG_Z);
        let right = forward.cross(Vec3::Y).normalize_or(Vec3::X);
        let up = right.cross(forward);
        (forward, right, up)
    }

    /// Turns the eye around the target: `d_yaw` about world Y, `d_pitch` up and down (radians).
    pub fn orbit(&mut self, d_yaw: f32, d_pitch: f32) {
        self.yaw = (self.yaw + d_yaw).rem_euclid(std::f32::consts::TAU);
        self.pitch = (self.pitch + d_pitch).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Slides eye and target together so the scene follows a cursor drag of `delta_px` pixels in a
    /// viewport `viewport_px` pixels tall (points at the target's depth move with the cursor).
    pub fn pan(&mut self, delta_px: Vec2, viewport_height_px: f32) {
        let (_, right, up) = self.basis();
        let metres_per_px =
            2.0 * self.distance * (self.fov_y_deg.to_radians() * 0.5).tan() / viewport_height_px.max(1.0);
        self.target += (-delta_px.x * right + delta_px.y * up) * metres_per_px;
    }

    /// Dolly: multiplies the distance by `factor` (below 1 moves closer), within sane bounds.
    pub fn zoom(&mut self, factor: f32) {
        if factor.is_finite() && factor > 0.0 {
            self.distance = (self.distance * factor).clamp(MIN_DISTANCE, MAX_DISTANCE);
        }
    }

    /// Near and far clip distances, scaled with the orbit distance to keep depth precision.
    pub fn clip_range(&self) -> (f32, f32) {
        (self.distance * 0.02, self.distance * 40.0)
    }

    /// World to view (right-handed, Y up, looking down −Z).
    pub fn view(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye(), self.target, Vec3::Y)
    }

    /// View to clip, wgpu's depth range `[0, 1]`, Y up in NDC.
    pub fn proj(&self, aspect: f32) -> Mat4 {
        let (near, far) = self.clip_range();
        let aspect = if aspect.is_finite() && aspect > 0.0 { aspect } else { 1.0 };
        glam::camera::rh::proj::directx::perspective(self.fov_y_deg.to_radians(), aspect, near, far)
    }

    /// World to clip for a viewport of the given width / height.
    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        self.proj(aspect) * self.view()
    }

    /// The pixel (origin top left, y down) where a world point lands, and its NDC depth; `None` behind
    /// the eye.
    pub fn project(&self, world: Vec3, viewport_px: Vec2) -> Option<(Vec2, f32)> {
        let clip = self.view_proj(viewport_px.x / viewport_px.y.max(1.0)) * world.extend(1.0);
        if clip.w <= 0.0 {
            return None;
        }
        let ndc = clip.truncate() / clip.w;
        let px = Vec2::new((ndc.x + 1.0) * 0.5 * viewport_px.x, (1.0 - ndc.y) * 0.5 * viewport_px.y);
        Some((px, ndc.z))
    }

    /// The picking ray under a cursor (pixels, origin top left, y down): origin on the near plane and a
    /// unit direction, world space.
    pub fn ray(&self, cursor_px: Vec2, viewport_px: Vec2) -> (Vec3, Vec3) {
        let w = viewport_px.x.max(1.0);
        let h = viewport_px.y.max(1.0);
        let ndc = Vec2::new(2.0 * cursor_px.x / w - 1.0, 1.0 - 2.0 * cursor_px.y / h);
        let inv = self.view_proj(w / h).inverse();
        let near = inv.project_point3(ndc.extend(0.0));
        let far = inv.project_point3(ndc.extend(1.0));
        (near, (far - near).normalize_or((self.target - self.eye()).normalize_or(Vec3::NEG_Z)))
    }
}

impl From<&CameraSpec> for OrbitCamera {
    fn from(spec: &CameraSpec) -> Self {
        Self::from_spec(spec)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> OrbitCamera {
        OrbitCamera::from_spec(&CameraSpec {
            eye: [0.03, 0.09, 0.1],
            target: [0.01, 0.0, -0.02],
            fov_y_deg: 40.0,
        })
    }

    #[test]
    fn spec_round_trips() {
        let spec = CameraSpec { eye: [0.03, 0.09, 0.1], target: [0.01, 0.0, -0.02], fov_y_deg: 40.0 };
        let back = OrbitCamera::from_spec(&spec).to_spec();
        for i in 0..3 {
            assert!((back.eye[i] - spec.eye[i]).abs() < 1e-5, "{back:?}");
        }
    }

    #[test]
    fn projected_point_lies_on_its_ray() {
        let cam = camera();
        let vp = Vec2::new(1280.0, 800.0);
        for p in [Vec3::ZERO, Vec3::new(0.03, 0.01, -0.04), Vec3::new(-0.04, -0.005, 0.02)] {
            let (px, depth) = cam.project(p, vp).expect("in front of the eye");
            assert!((0.0..=1.0).contains(&depth), "depth {depth}");
            let (o, d) = cam.ray(px, vp);
            assert!((d.length() - 1.0).abs() < 1e-4);
            let along = (p - o).dot(d);
            assert!(along > 0.0);
            let miss = (p - (o + along * d)).length();
            assert!(miss < 1e-5, "point {p} misses its ray by {miss} m");
        }
    }

    #[test]
    fn centre_ray_points_at_target() {
        let cam = camera();
        let (o, d) = cam.ray(Vec2::new(640.0, 400.0), Vec2::new(1280.0, 800.0));
        let to_target = (cam.target - o).normalize();
        assert!(d.dot(to_target) > 0.99999);
    }

    #[test]
    fn orbit_pan_zoom_keep_invariants() {
        let mut cam = camera();
        let d0 = cam.distance;
        cam.orbit(0.3, 10.0);
        assert!(cam.pitch <= MAX_PITCH);
        assert!((cam.eye() - cam.target).length() - d0 < 1e-5);
        let t0 = cam.target;
        cam.pan(Vec2::new(100.0, 0.0), 800.0);
        let (_, right, _) = cam.basis();
        assert!((cam.target - t0).dot(right) < 0.0, "dragging right moves the target left");
        cam.zoom(0.5);
        assert!((cam.distance - d0 * 0.5).abs() < 1e-6);
        cam.zoom(0.0);
        assert!((cam.distance - d0 * 0.5).abs() < 1e-6);
    }
}
