//! `csg` objects: each becomes one tree in [`crate::geometry::csg::Csg`] and
//! one BVH primitive. Operands are validated by the same helpers as plain
//! objects of their kind; what cannot bound a solid is an error naming the
//! operand's key path (`objects[3].csg.b`).
//!
//! - `sphere`, capped `cylinder`, `mesh` (closed: every edge shared by
//!   exactly two triangles) and nested `csg` are operands;
//! - a `group` is the union of its members;
//! - `plane`, `triangle` and uncapped cylinders bound no solid: errors.
//!
//! Transforms of enclosing nodes are folded into each leaf. Materials: the
//! outermost CSG object that names a `material` overrides every surface
//! below it; otherwise each operand keeps its own (or inherits, as in a
//! group). Point lights and cameras in a mesh file used as an operand are
//! ignored.

use super::mesh::mesh_triangles;
use super::object::Placement;
use super::Compiler;
use crate::error::InputResult;
use crate::geometry::csg::mesh::check_closed;
use crate::geometry::csg::CsgOp;
use crate::geometry::{AnalyticPrim, Shape, NO_TRANSFORM};
use crate::math::Transform;
use crate::scene::description::{self, CsgDesc, ObjectDesc};
use glam::Affine3A;

impl Compiler<'_> {
    /// A `csg` object at `key`: its tree and one primitive for the BVH,
    /// unless the bounds already prove it empty.
    pub(super) fn csg_object(
        &mut self,
        desc: &CsgDesc,
        key: &str,
        m: Affine3A,
        material: u32,
        explicit_material: Option<u32>,
    ) -> InputResult<()> {
        let root = self.csg_tree(desc, &format!("{key}.csg"), m, material, explicit_material)?;
        if self.csg.part_count() >= 1 << 31 {
            return Err(self.err(key, "too many CSG surfaces (2³¹ or more)"));
        }
        if !self.csg.bounds(root).is_empty() {
            self.shapes.push(AnalyticPrim {
                shape: Shape::Csg(root),
                transform: NO_TRANSFORM,
                material,
            });
        }
        Ok(())
    }

    /// The node for `a op b`; `forced` is the material of an enclosing CSG
    /// object that names one.
    fn csg_tree(
        &mut self,
        desc: &CsgDesc,
        key: &str,
        m: Affine3A,
        inherited: u32,
        forced: Option<u32>,
    ) -> InputResult<u32> {
        let a = self.csg_operand(&desc.a, &format!("{key}.a"), m, inherited, forced)?;
        let b = self.csg_operand(&desc.b, &format!("{key}.b"), m, inherited, forced)?;
        let op = match desc.op {
            description::CsgOp::Union => CsgOp::Union,
            description::CsgOp::Intersection => CsgOp::Intersection,
            description::CsgOp::Difference => CsgOp::Difference,
        };
        Ok(self.csg.push_op(op, a, b))
    }

    fn csg_operand(
        &mut self,
        obj: &ObjectDesc,
        key: &str,
        parent: Affine3A,
        inherited: u32,
        forced: Option<u32>,
    ) -> InputResult<u32> {
        let Placement {
            m,
            material,
            explicit_material,
        } = self.placement(obj, key, parent, inherited)?;
        self.no_imports(obj, key, "a CSG operand")?;
        let leaf_material = forced.unwrap_or(material);
        if let Some(s) = &obj.sphere {
            let sphere = self.sphere_desc(s, key)?;
            let (sphere, m) = self.placed_sphere(sphere, m, key)?;
            let transform = m.map(|m| self.leaf_transform(m, key)).transpose()?;
            Ok(self.csg.push_sphere(sphere, transform, leaf_material))
        } else if let Some(c) = &obj.cylinder {
            let (cylinder, place) = self.cylinder_desc(c, key)?;
            if !cylinder.caps {
                return Err(self.err(
                    &format!("{key}.cylinder.caps"),
                    "an uncapped cylinder is an open surface, not a solid; a CSG operand needs caps = true",
                ));
            }
            let transform = self.leaf_transform(m * place, key)?;
            Ok(self
                .csg
                .push_cylinder(cylinder, Some(transform), leaf_material))
        } else if let Some(file) = &obj.mesh {
            self.csg_mesh(file, key, m, forced.or(explicit_material), inherited)
        } else if let Some(members) = &obj.group {
            let mut nodes = Vec::with_capacity(members.len());
            for (i, member) in members.iter().enumerate() {
                let k = format!("{key}.group[{i}]");
                nodes.push(self.csg_operand(member, &k, m, material, forced)?);
            }
            if nodes.is_empty() {
                return Err(self.err(&format!("{key}.group"), "an empty group is not a solid"));
            }
            Ok(self.balanced_union(&nodes))
        } else if let Some(c) = &obj.csg {
            self.csg_tree(
                c,
                &format!("{key}.csg"),
                m,
                material,
                forced.or(explicit_material),
            )
        } else if obj.plane.is_some() {
            Err(self.err(
                &format!("{key}.plane"),
                "an infinite plane cannot be a CSG operand; use a closed solid (sphere, capped cylinder, closed mesh, group or csg)",
            ))
        } else {
            Err(self.err(
                &format!("{key}.triangle"),
                "a single triangle bounds no solid, so it cannot be a CSG operand; use a closed mesh",
            ))
        }
    }

    /// The union of `nodes` as a balanced tree, so that the nodes' boxes
    /// cull whole halves of a large group.
    fn balanced_union(&mut self, nodes: &[u32]) -> u32 {
        if nodes.len() == 1 {
            return nodes[0];
        }
        let (left, right) = nodes.split_at(nodes.len() / 2);
        let (a, b) = (self.balanced_union(left), self.balanced_union(right));
        self.csg.push_op(CsgOp::Union, a, b)
    }

    fn leaf_transform(&self, m: Affine3A, key: &str) -> InputResult<Transform> {
        Transform::new(m).ok_or_else(|| {
            self.err(
                &format!("{key}.transform"),
                "transform is singular or not finite",
            )
        })
    }

    /// A closed mesh operand: every triangle of the file, baked into world
    /// space, with the file's materials unless `explicit` overrides them.
    fn csg_mesh(
        &mut self,
        file: &str,
        key: &str,
        m: Affine3A,
        explicit: Option<u32>,
        inherited: u32,
    ) -> InputResult<u32> {
        let (asset, first_material, path) = self.asset(file, &format!("{key}.mesh"))?;
        let mut tris = Vec::new();
        let mut materials = Vec::new();
        for mesh in asset.baked_meshes().iter() {
            let material = explicit
                .or(mesh.material.map(|i| first_material + i as u32))
                .unwrap_or(inherited);
            let mesh_tris = mesh_triangles(mesh, &path)?;
            materials.resize(materials.len() + mesh_tris.len(), material);
            tris.extend(mesh_tris);
        }
        if tris.is_empty() {
            return Err(self.err(
                &format!("{key}.mesh"),
                format!("'{file}' has no triangles, so it bounds no solid"),
            ));
        }
        if let Err(open) = check_closed(&tris) {
            return Err(self.err(
                &format!("{key}.mesh"),
                format!(
                    "'{file}' is not a closed mesh, so it cannot be a CSG operand: the edge from {:?} to {:?} belongs to {} triangle(s), and every edge must belong to exactly two",
                    open.from.to_array(),
                    open.to.to_array(),
                    open.uses
                ),
            ));
        }
        let t = Transform::new(m).expect("checked by placement");
        let world: Vec<_> = tris.iter().map(|v| v.map(|p| t.point(p))).collect();
        if world.iter().flatten().any(|p| !p.is_finite()) {
            return Err(self.err(key, "mesh is not finite after its transform"));
        }
        Ok(self.csg.push_mesh(world, materials))
    }
}
