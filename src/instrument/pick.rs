//! Picking: a ray against the tissue's current triangles, through parry3d. The picker keeps its
//! buffers and is refreshed from the snapshot each frame, so it follows deformation and cuts.

use parry3d::math::{Vec3, Vector};
use parry3d::query::{Ray, RayCast};
use parry3d::shape::TriMesh;

use crate::snapshot::Snapshot;

/// Where a ray met the tissue.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// World point of the hit.
    pub point: [f32; 3],
    /// Layer index in the snapshot (0 is the upper layer).
    pub layer: usize,
    /// Vertex of the layer's mesh nearest the hit.
    pub vertex: u32,
    /// Distance along the ray.
    pub distance: f32,
}

/// Ray casting against the layers of a snapshot.
#[derive(Default)]
pub struct Picker {
    meshes: Vec<Option<TriMesh>>,
}

impl Picker {
    /// Rebuilds the acceleration structures from a snapshot's layers.
    pub fn refresh(&mut self, snapshot: &Snapshot) {
        self.meshes.clear();
        for layer in &snapshot.layers {
            let vertices: Vec<Vec3> = layer.positions.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect();
            let indices = layer.triangles.clone();
            self.meshes.push(if indices.is_empty() { None } else { TriMesh::new(vertices, indices).ok() });
        }
    }

    /// The first layer hit by a ray from `origin` along `dir` (world), if any.
    pub fn cast(&self, snapshot: &Snapshot, origin: [f32; 3], dir: [f32; 3]) -> Option<Hit> {
        let ray = Ray::new(Vec3::new(origin[0], origin[1], origin[2]), Vector::new(dir[0], dir[1], dir[2]));
        let mut best: Option<Hit> = None;
        for (li, mesh) in self.meshes.iter().enumerate() {
            let Some(mesh) = mesh else { continue };
            let Some(hit) = mesh.cast_local_ray_and_get_normal(&ray, f32::MAX, false) else { continue };
            if best.is_some_and(|b| b.distance <= hit.time_of_impact) {
                continue;
            }
            let p = ray.point_at(hit.time_of_impact);
            let point = [p.x, p.y, p.z];
            let layer = snapshot.layers.get(li)?;
            // The vertex nearest the hit point (the face id of a hit is not an index into our
            // triangle list once parry has built its tree, so it is not used).
            let vertex = (0..layer.positions.len() as u32)
                .min_by(|&a, &b| {
                    dist2(layer.positions[a as usize], point)
                        .total_cmp(&dist2(layer.positions[b as usize], point))
                })
                .unwrap_or(0);
            best = Some(Hit { point, layer: li, vertex, distance: hit.time_of_impact });
        }
        best
    }
}

fn dist2(a: [f32; 3], b: [f32; 3]) -> f32 {
    glam::Vec3::from(a).distance_squared(glam::Vec3::from(b))
}
