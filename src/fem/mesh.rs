//! The tetrahedral mesh: a block of `nx × ny × nz` grid nodes (numbered x fastest, as the ChainMail
//! [`Lattice::volume`](crate::chainmail::Lattice::volume)), each cube cut into 5 or 6 tetrahedra so that
//! neighbouring cubes share their face diagonals (a conforming mesh).

use serde::{Deserialize, Serialize};

use super::error::{FemError, finite};

/// Most nodes a mesh may hold (about 1 Mi nodes; the dense condensed inverse runs out of memory far
/// earlier, see [`LoadOptions`](super::LoadOptions)).
pub const MAX_NODES: usize = 1 << 20;

macro_rules! typed_id {
    ($(#[$doc:meta])* $name:ident) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Default, Serialize, Deserialize)]
        pub struct $name(pub u32);

        impl $name {
            /// The id as an index into the per-item arrays.
            #[inline]
            pub fn index(self) -> usize {
                self.0 as usize
            }
        }
    };
}

typed_id!(
    /// A node of the mesh. For a block it has the same number as the ChainMail element at the same grid
    /// position.
    NodeId
);
typed_id!(
    /// A tetrahedron of the mesh.
    TetId
);

/// How each grid cube is cut into tetrahedra.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
pub enum Split {
    /// Five tetrahedra (four corner ones and a central one), mirrored in every other cube so that the
    /// face diagonals match.
    Five,
    /// Six tetrahedra around the main diagonal (Kuhn's split); the same in every cube.
    #[default]
    Six,
}

/// A face of the block.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Face {
    /// x = 0.
    XMin,
    /// x = max.
    XMax,
    /// y = 0 (the base, Y being up).
    YMin,
    /// y = max (the top).
    YMax,
    /// z = 0.
    ZMin,
    /// z = max.
    ZMax,
}

impl Face {
    /// The axis normal to the face and whether it is the far side.
    pub fn axis_side(self) -> (usize, bool) {
        match self {
            Face::XMin => (0, false),
            Face::XMax => (0, true),
            Face::YMin => (1, false),
            Face::YMax => (1, true),
            Face::ZMin => (2, false),
            Face::ZMax => (2, true),
        }
    }
}

/// Nodes and linear tetrahedra of a block.
#[derive(Clone, Debug)]
pub struct TetMesh {
    dims: [usize; 3],
    spacing: f64,
    nodes: Vec<[f64; 3]>,
    tets: Vec<[u32; 4]>,
}

/// Corner `c` (bits: x = 1, y = 2, z = 4) of the cube at `(i, j, k)`.
fn corner(dims: [usize; 3], at: [usize; 3], c: usize) -> u32 {
    let (i, j, k) = (at[0] + (c & 1), at[1] + ((c >> 1) & 1), at[2] + ((c >> 2) & 1));
    (i + dims[0] * (j + dims[1] * k)) as u32
}

fn signed_volume(p: &[[f64; 3]], t: [u32; 4]) -> f64 {
    let o = p[t[0] as usize];
    let d = |n: u32| {
        let q = p[n as usize];
        [q[0] - o[0], q[1] - o[1], q[2] - o[2]]
    };
    let (a, b, c) = (d(t[1]), d(t[2]), d(t[3]));
    (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0]))
        / 6.0
}

impl TetMesh {
    /// A block of `dims` nodes with the given spacing (metres), starting at the origin, every cube cut
    /// by `split`. Tetrahedra are oriented with positive volume.
    pub fn block(dims: [usize; 3], spacing: f64, split: Split) -> Result<Self, FemError> {
        if dims.iter().any(|&d| d < 2) {
            return Err(FemError::EmptyGrid { dims });
        }
        let count = dims.iter().fold(1u128, |a, &d| a.saturating_mul(d as u128));
        if count > MAX_NODES as u128 {
            return Err(FemError::TooBig {
                what: format!("a mesh of {count} nodes (limit {MAX_NODES} nodes)"),
                needed_mib: count as f64 * 24.0 / (1 << 20) as f64,
                limit_mib: MAX_NODES as f64 * 24.0 / (1 << 20) as f64,
            });
        }
        finite("spacing", spacing)?;
        if spacing <= 0.0 {
            return Err(FemError::BadParameter(format!(
                "spacing is {spacing} m, expected a positive length"
            )));
        }
        let [nx, ny, nz] = dims;
        let mut nodes = Vec::with_capacity(count as usize);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    nodes.push([i as f64 * spacing, j as f64 * spacing, k as f64 * spacing]);
                }
            }
        }
        const SIX: [[usize; 4]; 6] =
            [[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7]];
        const FIVE: [[usize; 4]; 5] = [[0, 1, 2, 4], [3, 1, 2, 7], [5, 1, 4, 7], [6, 2, 4, 7], [1, 2, 4, 7]];
        let per_cube = match split {
            Split::Five => 5,
            Split::Six => 6,
        };
        let mut tets = Vec::with_capacity((nx - 1) * (ny - 1) * (nz - 1) * per_cube);
        for k in 0..nz - 1 {
            for j in 0..ny - 1 {
                for i in 0..nx - 1 {
                    let at = [i, j, k];
                    let cube: &[[usize; 4]] = match split {
                        Split::Five => &FIVE,
                        Split::Six => &SIX,
                    };
                    // Mirror the five-tet split in every other cube so that face diagonals match.
                    let flip = if split == Split::Five && (i + j + k) % 2 == 1 { 1 } else { 0 };
                    for t in cube {
                        let mut tet = t.map(|c| corner(dims, at, c ^ flip));
                        if signed_volume(&nodes, tet) < 0.0 {
                            tet.swap(2, 3);
                        }
                        tets.push(tet);
                    }
                }
            }
        }
        Ok(Self { dims, spacing, nodes, tets })
    }

    /// Nodes along each axis.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Grid spacing, metres.
    pub fn spacing(&self) -> f64 {
        self.spacing
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Number of tetrahedra.
    pub fn tet_count(&self) -> usize {
        self.tets.len()
    }

    /// Rest positions of the nodes, metres.
    pub fn positions(&self) -> &[[f64; 3]] {
        &self.nodes
    }

    /// The four nodes of every tetrahedron.
    pub fn tets(&self) -> &[[u32; 4]] {
        &self.tets
    }

    /// The four corner positions of a tetrahedron.
    pub fn tet_corners(&self, t: TetId) -> Option<[[f64; 3]; 4]> {
        self.tets.get(t.index()).map(|tet| tet.map(|n| self.nodes[n as usize]))
    }

    /// The node at grid position `(i, j, k)`.
    pub fn node_at(&self, i: usize, j: usize, k: usize) -> Option<NodeId> {
        let [nx, ny, nz] = self.dims;
        (i < nx && j < ny && k < nz).then(|| NodeId((i + nx * (j + ny * k)) as u32))
    }

    /// Grid position of a node.
    pub fn grid_position(&self, n: NodeId) -> Option<[usize; 3]> {
        let i = n.index();
        let [nx, ny, _] = self.dims;
        (i < self.nodes.len()).then(|| [i % nx, (i / nx) % ny, i / (nx * ny)])
    }

    /// Whether a node lies on the boundary of the block.
    pub fn is_boundary(&self, n: NodeId) -> bool {
        self.grid_position(n).is_some_and(|g| (0..3).any(|a| g[a] == 0 || g[a] + 1 == self.dims[a]))
    }

    /// Whether a node lies on the given face.
    pub fn on_face(&self, n: NodeId, face: Face) -> bool {
        let (axis, far) = face.axis_side();
        self.grid_position(n).is_some_and(|g| if far { g[axis] + 1 == self.dims[axis] } else { g[axis] == 0 })
    }

    /// The triangles of the tetrahedra that lie on a face of the block, each oriented with its normal
    /// pointing out of the block.
    pub fn face_triangles(&self, face: Face) -> Vec<[u32; 3]> {
        const FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];
        let (axis, far) = face.axis_side();
        let mut out = Vec::new();
        for tet in &self.tets {
            for f in FACES {
                let tri = f.map(|c| tet[c]);
                if tri.iter().all(|&n| self.on_face(NodeId(n), face)) {
                    let [a, b, c] = tri.map(|n| self.nodes[n as usize]);
                    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
                    let normal =
                        [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
                    let outward = if far { normal[axis] > 0.0 } else { normal[axis] < 0.0 };
                    out.push(if outward { tri } else { [tri[0], tri[2], tri[1]] });
                }
            }
        }
        out
    }

    /// Volume of a tetrahedron, cubic metres.
    pub fn tet_volume(&self, t: TetId) -> Option<f64> {
        self.tets.get(t.index()).map(|&tet| signed_volume(&self.nodes, tet))
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::*;

    fn check_conforming(split: Split) {
        let mesh = TetMesh::block([4, 3, 5], 0.5, split).expect("mesh");
        let total: f64 = (0..mesh.tet_count()).map(|t| mesh.tet_volume(TetId(t as u32)).unwrap_or(0.0)).sum();
        assert!((total - 1.5 * 1.0 * 2.0).abs() < 1e-12, "volume {total}");
        assert!((0..mesh.tet_count()).all(|t| mesh.tet_volume(TetId(t as u32)).unwrap_or(0.0) > 0.0));
        // Every face is shared by two tetrahedra, except the boundary ones: two per boundary square.
        let mut faces: HashMap<[u32; 3], u32> = HashMap::new();
        for tet in mesh.tets() {
            for skip in 0..4 {
                let mut f = [0u32; 3];
                let mut n = 0;
                for (c, &v) in tet.iter().enumerate() {
                    if c != skip {
                        f[n] = v;
                        n += 1;
                    }
                }
                f.sort_unstable();
                *faces.entry(f).or_default() += 1;
            }
        }
        assert!(faces.values().all(|&c| c <= 2));
        let boundary = faces.values().filter(|&&c| c == 1).count();
        let squares = 2 * (3 * 2 + 3 * 4 + 2 * 4);
        assert_eq!(boundary, 2 * squares, "{split:?}");
        let top = mesh.face_triangles(Face::YMax);
        assert_eq!(top.len(), 2 * 3 * 4);
    }

    #[test]
    fn six_split_is_conforming() {
        check_conforming(Split::Six);
    }

    #[test]
    fn five_split_is_conforming() {
        check_conforming(Split::Five);
    }

    #[test]
    fn bad_blocks_are_refused() {
        assert!(matches!(TetMesh::block([1, 3, 3], 1.0, Split::Six), Err(FemError::EmptyGrid { .. })));
        assert!(matches!(TetMesh::block([3, 3, 3], 0.0, Split::Six), Err(FemError::BadParameter(_))));
        assert!(matches!(TetMesh::block([3, 3, 3], f64::NAN, Split::Six), Err(FemError::NotFinite { .. })));
        assert!(matches!(TetMesh::block([2000, 2000, 2000], 1.0, Split::Six), Err(FemError::TooBig { .. })));
    }
}
