//! Picking: a ray against the tissue's current triangles, through parry3d. The picker keeps its
//! meshes and is refreshed from the snapshot each frame, so it follows deformation and cuts: a layer
//! whose triangles are unchanged keeps its tree and refits it to the new positions (at 128 x 96, about
//! 18 ms to build a layer pair's trees, a small part of that to refit them); a cut or a tear rebuilds it.

use parry3d::math::{Vec3, Vector};
use parry3d::query::{Ray, RayCast};
use parry3d::shape::{TriMesh, TriMeshFlags};

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
    /// Brings the acceleration structures to a snapshot's layers: refitted where a layer's triangles
    /// are those it was built with, rebuilt where they changed.
    pub fn refresh(&mut self, snapshot: &Snapshot) {
        self.meshes.truncate(snapshot.layers.len());
        for (i, layer) in snapshot.layers.iter().enumerate() {
            let vertex = |p: &[f32; 3]| Vec3::new(p[0], p[1], p[2]);
            let kept = self.meshes.get_mut(i).and_then(Option::as_mut).filter(|m| {
                m.indices() == layer.triangles.as_slice() && m.vertices().len() == layer.positions.len()
            });
            if let Some(mesh) = kept {
                mesh.update_vertices(|v| {
                    for (v, p) in v.iter_mut().zip(&layer.positions) {
                        *v = vertex(p);
                    }
                });
                continue;
            }
            let mesh = if layer.triangles.is_empty() {
                None
            } else {
                let vertices = layer.positions.iter().map(vertex).collect();
                TriMesh::with_flags(vertices, layer.triangles.clone(), TriMeshFlags::DEFORMABLE).ok()
            };
            match self.meshes.get_mut(i) {
                Some(m) => *m = mesh,
                None => self.meshes.push(mesh),
            }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::snapshot::LayerMesh;

    /// A unit square at height `y` (two triangles), as a snapshot of one layer.
    fn square(y: f32, triangles: Vec<[u32; 3]>) -> Snapshot {
        let positions = vec![[0.0, y, 0.0], [1.0, y, 0.0], [1.0, y, 1.0], [0.0, y, 1.0]];
        Snapshot {
            layers: vec![LayerMesh { positions, triangles, ..Default::default() }],
            ..Default::default()
        }
    }

    fn height_under(picker: &Picker, snapshot: &Snapshot, x: f32, z: f32) -> Option<f32> {
        picker.cast(snapshot, [x, 10.0, z], [0.0, -1.0, 0.0]).map(|h| h.point[1])
    }

    #[test]
    fn a_refitted_picker_follows_the_tissue_and_a_changed_mesh_is_rebuilt() {
        let both = vec![[0, 1, 2], [0, 2, 3]];
        let mut picker = Picker::default();
        let flat = square(0.0, both.clone());
        picker.refresh(&flat);
        assert_eq!(height_under(&picker, &flat, 0.7, 0.2), Some(0.0));
        // The same triangles moved: refitted, the ray meets them where they are now.
        let lifted = square(2.0, both);
        picker.refresh(&lifted);
        let h = height_under(&picker, &lifted, 0.7, 0.2).expect("a hit on the lifted square");
        assert!((h - 2.0).abs() < 1e-5, "{h}");
        // One triangle cut away: rebuilt, the ray passes where it was.
        let half = square(2.0, vec![[0, 2, 3]]);
        picker.refresh(&half);
        assert_eq!(height_under(&picker, &half, 0.7, 0.2), None);
        assert!(height_under(&picker, &half, 0.2, 0.7).is_some());
        // No layers: nothing to hit.
        picker.refresh(&Snapshot::default());
        assert_eq!(height_under(&picker, &half, 0.2, 0.7), None);
    }
}
