//! Parametric surfaces `X(u, v)` that SurfaceChainMail maps its lattice onto: a plane (a box face), a
//! cylinder (wrapping in `u`) and a sphere (wrapping in `u`, poles left out of the lattice so that no link
//! is degenerate).
//!
//! Where they lie (with `u`, `v` as fractions of their range): a plane in `y = 0` with `x = (u − ½)·width`,
//! `z = (v − ½)·depth`; a cylinder along x with `x = (v − ½)·length`, `y = −r·cos 2πu`, `z = r·sin 2πu`
//! (the seam underneath, `u = ½` on top); a sphere with `y = −r·cos πv` (south pole at `v = 0`) and
//! `x = −ρ·sin 2πu`, `z = −ρ·cos 2πu`, `ρ = r·sin πv`.
//!
//! Lattice coordinates are `(u, v, h)`: `u` and `v` are arc lengths on the base surface (metres, so
//! that relative limits mean the same in both directions) and `h` the offset along the surface normal.
//! A point maps to `X(u, v) + h·N(u, v)`. The normal at an element is the average of the normals of the
//! four facets around it; for these surfaces that average equals the analytic normal (a symmetric
//! stencil; tested), which the hot path uses so that the mapping has an exact inverse.
//!
//! Must not import wgpu, winit or egui, nor any dissect module but [`crate::chainmail`].

use std::f32::consts::PI;

use serde::{Deserialize, Serialize};

/// A base surface. Sizes in metres; the surface is centred on the origin with Y up.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum Surface {
    /// A horizontal rectangle in the XZ plane at y = 0, normal +Y.
    Plane {
        /// Extent along X (the `u` direction), metres.
        width: f32,
        /// Extent along Z (the `v` direction), metres.
        depth: f32,
    },
    /// The top face of a box-shaped block: the same mapping as a plane, with a block of `height` drawn
    /// below it.
    Box {
        /// Extent along X, metres.
        width: f32,
        /// Extent along Z, metres.
        depth: f32,
        /// Height of the block under the face, metres (drawn only).
        height: f32,
    },
    /// A cylinder around the Y axis; `u` runs around it (wrapping), `v` along it.
    Cylinder {
        /// Radius, metres.
        radius: f32,
        /// Length along Y, metres.
        length: f32,
    },
    /// A sphere around the origin; `u` runs around the Y axis (wrapping), `v` from the north pole down.
    Sphere {
        /// Radius, metres.
        radius: f32,
    },
}

/// The sampling of a surface: where the lattice's rest coordinates lie.
#[derive(Clone, Debug, PartialEq)]
pub struct Sampling {
    /// Rest `u` of each column, metres of arc.
    pub u: Vec<f32>,
    /// Rest `v` of each row, metres of arc.
    pub v: Vec<f32>,
    /// Period of `u` for surfaces that wrap.
    pub u_period: Option<f32>,
}

impl Surface {
    /// Checks sizes: finite and positive.
    pub fn validate(&self) -> Result<(), String> {
        let sizes: &[(&str, f32)] = match *self {
            Surface::Plane { width, depth } => &[("width", width), ("depth", depth)],
            Surface::Box { width, depth, height } => {
                &[("width", width), ("depth", depth), ("height", height)]
            }
            Surface::Cylinder { radius, length } => &[("radius", radius), ("length", length)],
            Surface::Sphere { radius } => &[("radius", radius)],
        };
        for &(name, x) in sizes {
            if !(x.is_finite() && x > 0.0) {
                return Err(format!("{name} is {x}, expected a positive number of metres"));
            }
        }
        Ok(())
    }

    /// Whether `u` wraps around (cylinder, sphere): the last element joins the first.
    pub fn wraps_u(&self) -> bool {
        matches!(self, Surface::Cylinder { .. } | Surface::Sphere { .. })
    }

    /// Half the largest extent of the surface (metres): a radius that contains it, for cameras.
    pub fn half_extent(&self) -> f32 {
        match *self {
            Surface::Plane { width, depth } => 0.5 * width.max(depth),
            Surface::Box { width, depth, height } => 0.5 * width.max(depth).max(height),
            Surface::Cylinder { radius, length } => radius.max(0.5 * length),
            Surface::Sphere { radius } => radius,
        }
    }

    /// Period of `u`, for surfaces that wrap.
    pub fn u_period(&self) -> Option<f32> {
        match *self {
            Surface::Cylinder { radius, .. } | Surface::Sphere { radius } => Some(2.0 * PI * radius),
            _ => None,
        }
    }

    /// Rest coordinates for `nu × nv` elements. `u_frac` and `v_frac` optionally give non-uniform
    /// positions as strictly increasing fractions in `[0, 1]` (of the span; for a wrapped `u`, of the
    /// period, the last below 1).
    pub fn sample(&self, nu: usize, nv: usize, u_frac: Option<&[f32]>, v_frac: Option<&[f32]>) -> Sampling {
        let uniform = |n: usize, closed: bool| -> Vec<f32> {
            (0..n)
                .map(|i| if closed { i as f32 / (n.max(2) - 1) as f32 } else { i as f32 / n as f32 })
                .collect()
        };
        let period = self.u_period();
        let uf = u_frac.map(<[f32]>::to_vec).unwrap_or_else(|| uniform(nu, period.is_none()));
        let (u0, u_span) = match *self {
            Surface::Plane { width, .. } | Surface::Box { width, .. } => (-0.5 * width, width),
            Surface::Cylinder { radius, .. } | Surface::Sphere { radius } => (0.0, 2.0 * PI * radius),
        };
        let u = uf.iter().map(|f| u0 + f * u_span).collect();
        let v = match *self {
            Surface::Plane { depth, .. } | Surface::Box { depth, .. } => {
                let vf = v_frac.map(<[f32]>::to_vec).unwrap_or_else(|| uniform(nv, true));
                vf.iter().map(|f| (f - 0.5) * depth).collect()
            }
            Surface::Cylinder { length, .. } => {
                let vf = v_frac.map(<[f32]>::to_vec).unwrap_or_else(|| uniform(nv, true));
                vf.iter().map(|f| (f - 0.5) * length).collect()
            }
            Surface::Sphere { radius } => {
                // Cell-centred rows: the poles are not lattice rows, so no link collapses to a point.
                let margin = 0.5 / nv as f32;
                let vf = v_frac
                    .map(<[f32]>::to_vec)
                    .unwrap_or_else(|| (0..nv).map(|j| (j as f32 + 0.5) / nv as f32).collect());
                vf.iter().map(|f| radius * PI * (margin + f * (1.0 - 2.0 * margin))).collect()
            }
        };
        Sampling { u, v, u_period: period }
    }

    /// The base surface point at `(u, v)`.
    #[inline]
    pub fn point(&self, u: f32, v: f32) -> [f32; 3] {
        match *self {
            Surface::Plane { .. } | Surface::Box { .. } => [u, 0.0, v],
            Surface::Cylinder { radius, .. } => {
                let t = u / radius;
                [v, -radius * t.cos(), radius * t.sin()]
            }
            Surface::Sphere { radius } => {
                let (t, f) = (u / radius, v / radius);
                let rho = radius * f.sin();
                [-rho * t.sin(), -radius * f.cos(), -rho * t.cos()]
            }
        }
    }

    /// The unit normal at `(u, v)`, pointing away from the inside (up for a plane).
    #[inline]
    pub fn normal(&self, u: f32, v: f32) -> [f32; 3] {
        match *self {
            Surface::Plane { .. } | Surface::Box { .. } => [0.0, 1.0, 0.0],
            Surface::Cylinder { radius, .. } => {
                let t = u / radius;
                [0.0, -t.cos(), t.sin()]
            }
            Surface::Sphere { radius } => {
                let (t, f) = (u / radius, v / radius);
                [-f.sin() * t.sin(), -f.cos(), -f.sin() * t.cos()]
            }
        }
    }

    /// The average of the normals of the four facets around `(u, v)` of a mesh with spacing
    /// `(du, dv)`, as the paper defines the normal at an element.
    pub fn facet_normal(&self, u: f32, v: f32, du: f32, dv: f32) -> [f32; 3] {
        let c = self.point(u, v);
        let ring =
            [self.point(u + du, v), self.point(u, v + dv), self.point(u - du, v), self.point(u, v - dv)];
        let mut n = [0.0f32; 3];
        for k in 0..4 {
            let (a, b) = (sub(ring[k], c), sub(ring[(k + 1) % 4], c));
            let f = normalize(cross(a, b));
            for i in 0..3 {
                n[i] += f[i];
            }
        }
        let n = normalize(n);
        // Orient like the analytic normal.
        let m = self.normal(u, v);
        if dot(n, m) < 0.0 { [-n[0], -n[1], -n[2]] } else { n }
    }

    /// Whether the surface is flat (a plane or a box's top), where [`Surface::flat_to_world`] maps.
    #[inline]
    pub fn is_flat(&self) -> bool {
        matches!(self, Surface::Plane { .. } | Surface::Box { .. })
    }

    /// [`Surface::to_world`] of a flat surface: its point `(u, 0, v)` plus `h` along its normal
    /// `(0, 1, 0)` is the lattice coordinates permuted (up to the sign of a zero coordinate, so every
    /// length between two points is the same bit for bit), without the general map's match and
    /// products, for loops over many links.
    #[inline]
    pub fn flat_to_world(p: [f32; 3]) -> [f32; 3] {
        [p[0], p[2], p[1]]
    }

    /// World position of lattice coordinates `(u, v, h)`.
    #[inline]
    pub fn to_world(&self, p: [f32; 3]) -> [f32; 3] {
        let x = self.point(p[0], p[1]);
        let n = self.normal(p[0], p[1]);
        [x[0] + p[2] * n[0], x[1] + p[2] * n[1], x[2] + p[2] * n[2]]
    }

    /// Lattice coordinates `(u, v, h)` of a world point. For a wrapped `u`, the value nearest `u_hint`
    /// modulo the period is returned, so an element crossing the seam keeps a continuous `u`.
    pub fn to_lattice(&self, p: [f32; 3], u_hint: f32) -> [f32; 3] {
        match *self {
            Surface::Plane { .. } | Surface::Box { .. } => [p[0], p[2], p[1]],
            Surface::Cylinder { radius, .. } => {
                let t = p[2].atan2(-p[1]);
                let r = (p[1] * p[1] + p[2] * p[2]).sqrt();
                [unwrap(radius * t, u_hint, 2.0 * PI * radius), p[0], r - radius]
            }
            Surface::Sphere { radius } => {
                let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt().max(1e-12);
                let f = (-p[1] / r).clamp(-1.0, 1.0).acos();
                let t = (-p[0]).atan2(-p[2]);
                [unwrap(radius * t, u_hint, 2.0 * PI * radius), radius * f, r - radius]
            }
        }
    }
}

fn unwrap(u: f32, hint: f32, period: f32) -> f32 {
    u + ((hint - u) / period).round() * period
}

#[inline]
fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[inline]
fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
fn normalize(a: [f32; 3]) -> [f32; 3] {
    let l = dot(a, a).sqrt();
    if l > 0.0 { [a[0] / l, a[1] / l, a[2] / l] } else { a }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn surfaces() -> [Surface; 3] {
        [
            Surface::Plane { width: 0.1, depth: 0.08 },
            Surface::Cylinder { radius: 0.03, length: 0.1 },
            Surface::Sphere { radius: 0.04 },
        ]
    }

    #[test]
    fn a_flat_surface_maps_lengths_as_its_general_map_does() {
        let flat = [
            Surface::Plane { width: 0.1, depth: 0.08 },
            Surface::Box { width: 0.08, depth: 0.06, height: 0.02 },
        ];
        let points = [
            [0.013f32, -0.027, 0.0031],
            [-0.041, 0.0093, -0.0007],
            [0.0, -0.0, 0.0],
            [0.0312, 0.0288, 0.0119],
        ];
        for s in flat {
            assert!(s.is_flat());
            for a in points {
                for b in points {
                    let (wa, wb) = (s.to_world(a), s.to_world(b));
                    let (fa, fb) = (Surface::flat_to_world(a), Surface::flat_to_world(b));
                    let d2 = |p: [f32; 3], q: [f32; 3]| {
                        (p[0] - q[0]) * (p[0] - q[0])
                            + (p[1] - q[1]) * (p[1] - q[1])
                            + (p[2] - q[2]) * (p[2] - q[2])
                    };
                    assert_eq!(d2(wa, wb).to_bits(), d2(fa, fb).to_bits());
                }
            }
        }
        assert!(surfaces()[1..].iter().all(|s| !s.is_flat()));
    }

    #[test]
    fn mapping_round_trips() {
        for s in surfaces() {
            for &(u, v, h) in &[(0.01f32, 0.02f32, 0.003f32), (0.05, 0.03, -0.001), (0.11, 0.06, 0.0)] {
                let w = s.to_world([u, v, h]);
                let back = s.to_lattice(w, u);
                for k in 0..3 {
                    assert!((back[k] - [u, v, h][k]).abs() < 2e-5, "{s:?}: {back:?} vs {:?}", [u, v, h]);
                }
            }
        }
    }

    #[test]
    fn facet_average_equals_the_analytic_normal() {
        for s in surfaces() {
            for &(u, v) in &[(0.013f32, 0.021f32), (0.07, 0.05)] {
                let f = s.facet_normal(u, v, 0.004, 0.003);
                let n = s.normal(u, v);
                assert!(dot(f, n) > 1.0 - 1e-5, "{s:?} at ({u}, {v}): {f:?} vs {n:?}");
            }
        }
    }

    #[test]
    fn sphere_rows_avoid_the_poles() {
        let s = Surface::Sphere { radius: 1.0 };
        let sm = s.sample(16, 8, None, None);
        assert!(sm.v[0] > 0.0 && *sm.v.last().unwrap_or(&PI) < PI);
        assert_eq!(sm.u.len(), 16);
    }
}
