//! The meshes the nodes use, read after the walk, when every use is known:
//! a mesh that one node uses is baked into file space; a mesh that two or
//! more nodes use (under invertible transforms) is read once, in its own
//! space, and kept with one placement per node ([`SharedMesh`]), so that
//! the scene compiler stores it once and places it by instances. A use
//! under a singular transform, which no instance can place, is baked.

use super::Loader;
use crate::error::InputResult;
use crate::math::{Aabb, Transform};
use crate::scene::asset::{LoadedAsset, LoadedMesh, SharedMesh, SharedPlacement};
use glam::{Affine3A, Mat4};
use std::collections::HashMap;

/// A node's use of a mesh, in traversal order.
pub(super) struct MeshUse {
    pub(super) node: usize,
    /// Index into the file's `meshes`, checked.
    pub(super) mesh: usize,
    /// The node's world transform.
    pub(super) world: Mat4,
}

impl Loader<'_> {
    /// Read the meshes of `uses` into `asset`: baked where placed once,
    /// shared where placed more often, numbered in the order of the uses
    /// ([`SharedPlacement::at`]).
    pub(super) fn place_meshes(
        &self,
        uses: &[MeshUse],
        asset: &mut LoadedAsset,
    ) -> InputResult<()> {
        // The map an instance would place the mesh by, if it can.
        let placement = |u: &MeshUse| {
            let a = Affine3A::from_mat4(u.world);
            Transform::new(a).map(|_| a)
        };
        let mut placed = vec![0u32; self.root.meshes.len()];
        for u in uses.iter().filter(|u| placement(u).is_some()) {
            placed[u.mesh] += 1;
        }
        // Each shared mesh read so far: its index in `asset.shared` and
        // the box of its positions (None: it has no triangles).
        let mut read: HashMap<usize, Option<(usize, Aabb)>> = HashMap::new();
        let mut at = 0;
        for u in uses {
            let Some(to_file) = placement(u).filter(|_| placed[u.mesh] > 1) else {
                for part in self.mesh_parts(u, Some(u.node), asset)? {
                    asset.meshes.push(self.place(u.node, part, &u.world)?);
                    at += 1;
                }
                continue;
            };
            let entry = match read.get(&u.mesh) {
                Some(&entry) => entry,
                None => {
                    let parts = self.mesh_parts(u, None, asset)?;
                    let bounds = parts
                        .iter()
                        .flat_map(|p| &p.positions)
                        .fold(Aabb::EMPTY, |b, &p| b.grow(p));
                    let has_triangles = parts.iter().any(|p| !p.indices.is_empty());
                    let entry = has_triangles.then(|| {
                        asset.shared.push(SharedMesh {
                            parts,
                            placements: Vec::new(),
                        });
                        (asset.shared.len() - 1, bounds)
                    });
                    read.insert(u.mesh, entry);
                    entry
                }
            };
            let Some((s, bounds)) = entry else {
                continue;
            };
            // What a baked copy checks of every vertex: a box's corners
            // bound every point inside it under an affine map.
            let shared = &mut asset.shared[s];
            if !bounds
                .corners()
                .iter()
                .all(|&c| to_file.transform_point3(c).is_finite())
            {
                return Err(self.to_infinity(u.node, &shared.parts[0].name));
            }
            shared.placements.push(SharedPlacement { to_file, at });
            at += shared.parts.len();
        }
        Ok(())
    }

    /// The triangle primitives of the mesh `u` uses, in the mesh's own
    /// space, named by the mesh (or, for a mesh one node uses, that node).
    fn mesh_parts(
        &self,
        u: &MeshUse,
        node: Option<usize>,
        asset: &LoadedAsset,
    ) -> InputResult<Vec<LoadedMesh>> {
        let mesh = &self.root.meshes[u.mesh];
        let base_name = mesh
            .name
            .clone()
            .or_else(|| node.and_then(|n| self.root.nodes[n].name.clone()))
            .unwrap_or_else(|| format!("mesh{}", u.mesh));
        let mut parts = Vec::new();
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let name = if mesh.primitives.len() > 1 {
                format!("{base_name}[{p}]")
            } else {
                base_name.clone()
            };
            let location = format!("meshes[{}].primitives[{p}]", u.mesh);
            parts.extend(self.primitive(&location, primitive, name, asset)?);
        }
        Ok(parts)
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::*;

    /// Mesh 0 is used by nodes 0 and 2 (and by node 3, under a singular
    /// scale); mesh 1, of two primitives, by node 1 alone.
    #[test]
    fn a_mesh_several_nodes_use_is_kept_once_with_its_placements_in_node_order() {
        let b = triangle_builder();
        let prim = r#"{"attributes":{"POSITION":0},"indices":1}"#;
        let rest = format!(
            r#""meshes":[{{"name":"tri","primitives":[{prim}]}},{{"name":"once","primitives":[{prim},{prim}]}}],
            "nodes":[{{"mesh":0,"translation":[1,0,0]}},{{"mesh":1,"children":[2],"translation":[0,5,0]}},
                     {{"mesh":0,"scale":[2,2,-2]}},{{"mesh":0,"scale":[0,1,1]}}]"#
        );
        let asset = load_json(&b, &rest).unwrap();
        assert_eq!(asset.shared.len(), 1);
        let shared = &asset.shared[0];
        assert_eq!(shared.parts.len(), 1);
        assert_eq!(shared.parts[0].name, "tri");
        assert_eq!(
            shared.parts[0].positions,
            TRIANGLE.map(Vec3::from),
            "mesh space"
        );
        let at: Vec<usize> = shared.placements.iter().map(|p| p.at).collect();
        assert_eq!(at, [0, 3], "after node 0's use and node 1's two primitives");
        assert_close(
            shared.placements[1].to_file.translation.into(),
            Vec3::Y * 5.0,
        );
        let names: Vec<&str> = asset.meshes.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["once[0]", "once[1]", "tri"], "placed once: baked");
        assert_eq!(asset.triangle_count(), 5);
        // Copies in node order, the mirroring node's marked.
        let baked = asset.baked_meshes();
        let second: Vec<Vec3> = baked.iter().map(|m| m.positions[1]).collect();
        assert_eq!(
            second,
            [
                Vec3::new(1., 0., 0.) + Vec3::X,
                Vec3::new(1., 5., 0.),
                Vec3::new(1., 5., 0.),
                Vec3::new(2., 5., 0.),
                Vec3::ZERO,
            ]
        );
        let mirrored: Vec<bool> = baked.iter().map(|m| m.mirrored).collect();
        assert_eq!(mirrored, [false, false, false, true, false]);
        assert_eq!(asset.clone().into_baked().meshes, baked.to_vec());
        // Bounds and framing see every placement.
        let used: Vec<Vec3> = asset.used_positions().collect();
        assert!(used.contains(&Vec3::new(2., 5., 0.)) && used.contains(&Vec3::new(2., 0., 0.)));
        assert!(used
            .iter()
            .all(|p| baked.iter().any(|m| m.positions.contains(p))));
    }

    #[test]
    fn a_shared_placement_past_f32_is_an_error_naming_its_node() {
        let b = triangle_builder();
        let rest = format!(
            r#"{TRIANGLE_MESH},"nodes":[{{"mesh":0}},{{"mesh":0,"scale":[3e38,1,1],"translation":[3e38,0,0]}}]"#
        );
        expect_error(
            load_json(&b, &rest),
            "scene.gltf",
            "nodes[1]",
            "to infinity",
        );
    }
}
