//! `[[objects]]`: placement (transform and material, inherited through
//! groups), then the shape: spheres and cylinders stay analytic in their
//! own space, planes stay outside the BVH, triangles and meshes are baked
//! into world space, groups recurse and CSG objects go to [`super::csg`].

use super::mesh::{MeshOrigin, TriangleSource};
use super::Compiler;
use crate::error::InputResult;
use crate::geometry::{AnalyticPrim, Shape, NO_TRANSFORM};
use crate::math::{Frame, Transform};
use crate::scene::description::{CylinderDesc, ObjectDesc, ScaleDesc, SphereDesc, TransformDesc};
use crate::scene::loaders;
use crate::shape::cylinder::Cylinder;
use crate::shape::plane::Plane;
use crate::shape::sphere::Sphere;
use glam::{Affine3A, Mat3, Mat4, Quat, Vec3};
use std::path::Path;

/// The word for an object's shape, for messages.
fn shape_word(obj: &ObjectDesc) -> &'static str {
    match obj {
        ObjectDesc {
            sphere: Some(_), ..
        } => "sphere",
        ObjectDesc { plane: Some(_), .. } => "plane",
        ObjectDesc {
            cylinder: Some(_), ..
        } => "cylinder",
        ObjectDesc {
            triangle: Some(_), ..
        } => "triangle",
        ObjectDesc { group: Some(_), .. } => "group",
        ObjectDesc { csg: Some(_), .. } => "csg object",
        _ => "mesh",
    }
}

/// An object's transform and material, after [`Compiler::placement`].
pub(super) struct Placement {
    /// Object to world, including every enclosing transform.
    pub(super) m: Affine3A,
    /// Its own material, or the inherited one.
    pub(super) material: u32,
    /// Its own `material` key, if it has one.
    pub(super) explicit_material: Option<u32>,
}

impl Compiler<'_> {
    pub(super) fn transform(&self, t: &TransformDesc, key: &str) -> InputResult<Affine3A> {
        if let Some(m) = t.matrix {
            if t.translate.is_some() || t.rotate.is_some() || t.scale.is_some() {
                return Err(self.err(
                    key,
                    "give either `matrix` or translate/rotate/scale, not both",
                ));
            }
            let mk = format!("{key}.matrix");
            if m.iter().flatten().any(|x| !x.is_finite()) {
                return Err(self.err(&mk, "must be finite"));
            }
            if m[3] != [0.0, 0.0, 0.0, 1.0] {
                return Err(self.err(
                    &mk,
                    "last row must be [0, 0, 0, 1] (affine transforms only)",
                ));
            }
            // Row-major in the file; glam is column-major.
            return Ok(Affine3A::from_mat4(
                Mat4::from_cols_array_2d(&m).transpose(),
            ));
        }
        let translate = match t.translate {
            Some(v) => self.v3(v, &format!("{key}.translate"))?,
            None => Vec3::ZERO,
        };
        let rotate = match t.rotate {
            Some([x, y, z, deg]) => {
                let rk = format!("{key}.rotate");
                let axis = self.direction([x, y, z], &rk)?;
                Quat::from_axis_angle(axis, self.finite(deg, &rk)?.to_radians())
            }
            None => Quat::IDENTITY,
        };
        let scale = match t.scale {
            Some(ScaleDesc::Uniform(s)) => Vec3::splat(s),
            Some(ScaleDesc::PerAxis(v)) => Vec3::from(v),
            None => Vec3::ONE,
        };
        if !scale.is_finite() || scale.abs().min_element() == 0.0 {
            return Err(self.err(
                &format!("{key}.scale"),
                format!(
                    "must be finite and non-zero, got {}",
                    super::validate::written(scale)
                ),
            ));
        }
        Ok(Affine3A::from_scale_rotation_translation(
            scale, rotate, translate,
        ))
    }

    pub(super) fn push_transform(&mut self, m: Affine3A, key: &str) -> InputResult<u32> {
        let t = Transform::new(m)
            .ok_or_else(|| self.err(key, "transform is singular or not finite"))?;
        self.transforms.push(t);
        Ok(self.transforms.len() as u32 - 1)
    }

    /// The scene index of material `name`: a `[materials]` table, or
    /// `FILE:NAME` for material `NAME` of mesh file `FILE`, which is read
    /// here if no earlier object has read it, so that the order of objects
    /// does not matter.
    fn material_id(&mut self, name: &str, key: &str) -> InputResult<u32> {
        if let Some(&id) = self.material_ids.get(name) {
            return Ok(id);
        }
        match name.rsplit_once(':') {
            Some((file, _)) if loaders::check_extension(Path::new(file)).is_ok() => {
                self.asset(file, key)?;
                let id = self.material_ids.get(name).copied();
                id.ok_or_else(|| self.err(key, self.unknown_material(name)))
            }
            _ => Err(self.err(key, self.unknown_material(name))),
        }
    }

    /// "unknown material 'flor'; did you mean 'floor'?", among the
    /// `[materials]` tables' names (a mesh file's own are `FILE:NAME`).
    fn unknown_material(&self, name: &str) -> String {
        let mut names: Vec<&str> = self
            .material_ids
            .keys()
            .map(String::as_str)
            .filter(|n| !n.contains(':'))
            .collect();
        names.sort_unstable();
        match names.is_empty() {
            true => format!("unknown material '{name}' (the scene has no [materials] tables)"),
            false => crate::mode::unknown("material", name, &names),
        }
    }

    /// What every object has besides its shape: exactly one shape key, a
    /// known material (or the inherited one) and an invertible transform.
    pub(super) fn placement(
        &mut self,
        obj: &ObjectDesc,
        key: &str,
        parent: Affine3A,
        inherited: u32,
    ) -> InputResult<Placement> {
        let shapes = [
            obj.sphere.is_some(),
            obj.plane.is_some(),
            obj.cylinder.is_some(),
            obj.triangle.is_some(),
            obj.mesh.is_some(),
            obj.group.is_some(),
            obj.csg.is_some(),
        ];
        match shapes.iter().filter(|&&s| s).count() {
            1 => {}
            0 => {
                return Err(self.err(
                    key,
                    "needs one of sphere, plane, cylinder, triangle, mesh, group or csg",
                ));
            }
            _ => return Err(self.err(key, "has more than one shape key; use a group for several")),
        }
        let explicit_material = match &obj.material {
            Some(name) => Some(self.material_id(name, &format!("{key}.material"))?),
            None => None,
        };
        let m = match &obj.transform {
            Some(t) => parent * self.transform(t, &format!("{key}.transform"))?,
            None => parent,
        };
        if Transform::new(m).is_none() {
            return Err(self.err(
                &format!("{key}.transform"),
                "transform is singular or not finite",
            ));
        }
        Ok(Placement {
            m,
            material: explicit_material.unwrap_or(inherited),
            explicit_material,
        })
    }

    pub(super) fn object(
        &mut self,
        obj: &ObjectDesc,
        key: &str,
        parent: Affine3A,
        inherited: u32,
    ) -> InputResult<()> {
        let Placement {
            m,
            material,
            explicit_material,
        } = self.placement(obj, key, parent, inherited)?;
        if obj.mesh.is_none() {
            self.no_imports(obj, key, &format!("a {}", shape_word(obj)))?;
        }
        for m in self.placements(obj, key, m)? {
            self.shape(obj, key, m, material, explicit_material)?;
        }
        Ok(())
    }

    /// The object's shape under one of its placements.
    fn shape(
        &mut self,
        obj: &ObjectDesc,
        key: &str,
        m: Affine3A,
        material: u32,
        explicit_material: Option<u32>,
    ) -> InputResult<()> {
        if let Some(s) = &obj.sphere {
            let sphere = self.sphere_desc(s, key)?;
            self.sphere(sphere, m, material, key)?;
        } else if let Some(p) = &obj.plane {
            let point = self.v3(p.point, &format!("{key}.plane.point"))?;
            let normal = self.direction(p.normal, &format!("{key}.plane.normal"))?;
            let t = Transform::new(m).expect("checked above");
            self.planes.push(Plane {
                point: t.point(point),
                normal: t.normal(normal),
                material,
            });
        } else if let Some(cyl) = &obj.cylinder {
            let (cylinder, place) = self.cylinder_desc(cyl, key)?;
            let t = self.push_transform(m * place, &format!("{key}.transform"))?;
            self.shapes.push(AnalyticPrim {
                shape: Shape::Cylinder(cylinder),
                transform: t,
                material,
            });
        } else if let Some(tri) = &obj.triangle {
            let mut v = [Vec3::ZERO; 3];
            for (i, p) in tri.v.iter().enumerate() {
                v[i] = m.transform_point3(self.v3(*p, &format!("{key}.triangle.v[{i}]"))?);
            }
            let origin = MeshOrigin {
                key: key.to_string(),
                file: None,
            };
            self.push_mesh(
                (key.to_string(), origin),
                TriangleSource::Soup(vec![v]),
                material,
                None,
                (None, None),
                m.matrix3.determinant() < 0.0,
            );
        } else if let Some(file) = &obj.mesh {
            self.mesh_file(file, key, m, explicit_material, material)?;
            self.mesh_imports(obj, file, key, m)?;
        } else if let Some(children) = &obj.group {
            for (i, child) in children.iter().enumerate() {
                self.object(child, &format!("{key}.group[{i}]"), m, material)?;
            }
        } else if let Some(c) = &obj.csg {
            self.csg_object(c, key, m, material, explicit_material)?;
        }
        Ok(())
    }

    pub(super) fn sphere_desc(&self, s: &SphereDesc, key: &str) -> InputResult<Sphere> {
        Ok(Sphere {
            center: self.v3(s.center, &format!("{key}.sphere.center"))?,
            radius: self.positive(s.radius, &format!("{key}.sphere.radius"))?,
        })
    }

    /// The canonical cylinder (along +z from the origin) and the frame that
    /// places it at `base` along `axis`.
    pub(super) fn cylinder_desc(
        &self,
        cyl: &CylinderDesc,
        key: &str,
    ) -> InputResult<(Cylinder, Affine3A)> {
        let k = |f: &str| format!("{key}.cylinder.{f}");
        let base = self.v3(cyl.base, &k("base"))?;
        let axis = self.direction(cyl.axis, &k("axis"))?;
        let radius = self.positive(cyl.radius, &k("radius"))?;
        let height = self.positive(cyl.height, &k("height"))?;
        let f = Frame::from_z(axis);
        let place = Affine3A::from_mat3_translation(Mat3::from_cols(f.x, f.y, f.z), base);
        let cylinder = Cylinder {
            radius,
            height,
            caps: cyl.caps,
        };
        Ok((cylinder, place))
    }

    /// A sphere under `m`: baked into a new centre and radius when `m` is a
    /// similarity, else kept in object space with `m` returned.
    pub(super) fn placed_sphere(
        &self,
        s: Sphere,
        m: Affine3A,
        key: &str,
    ) -> InputResult<(Sphere, Option<Affine3A>)> {
        let Some(scale) = similarity_scale(&m) else {
            return Ok((s, Some(m)));
        };
        // Rotation, uniform scale and translation map a sphere to a sphere exactly.
        let baked = Sphere {
            center: m.transform_point3(s.center),
            radius: s.radius * scale,
        };
        if !(baked.center.is_finite() && baked.radius.is_finite() && baked.radius > 0.0) {
            return Err(self.err(key, "sphere is not finite after its transform"));
        }
        Ok((baked, None))
    }

    pub(super) fn sphere(
        &mut self,
        s: Sphere,
        m: Affine3A,
        material: u32,
        key: &str,
    ) -> InputResult<()> {
        let (sphere, transform) = self.placed_sphere(s, m, key)?;
        let transform = match transform {
            Some(m) => self.push_transform(m, &format!("{key}.transform"))?,
            None => NO_TRANSFORM,
        };
        self.shapes.push(AnalyticPrim {
            shape: Shape::Sphere(sphere),
            transform,
            material,
        });
        Ok(())
    }
}

/// The uniform scale factor if `m`'s linear part is a similarity (rotation
/// times uniform scale, no shear, no reflection issue for spheres).
fn similarity_scale(m: &Affine3A) -> Option<f32> {
    let c = [m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis];
    let l = [c[0].length(), c[1].length(), c[2].length()];
    let s = l[0];
    let tol = 1e-6 * s;
    let equal = (l[1] - s).abs() <= tol && (l[2] - s).abs() <= tol;
    let orthogonal = c[0].dot(c[1]).abs() <= tol * s
        && c[1].dot(c[2]).abs() <= tol * s
        && c[0].dot(c[2]).abs() <= tol * s;
    (equal && orthogonal && s > 0.0).then_some(s)
}
#[cfg(test)]
mod tests {
    use super::super::test_support::{compiled, rejected};
    use super::similarity_scale;
    use crate::geometry::{Shape, NO_TRANSFORM};
    use glam::{Affine3A, Quat, Vec3};

    #[test]
    fn a_mesh_files_material_can_be_named_before_the_mesh_is_placed() {
        use crate::scene::{scene_from_str, RenderOverrides};
        let at = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/t.toml");
        let compile = |text: &str| scene_from_str(text, &at, &RenderOverrides::default());
        let sphere = "sphere = { center = [0.0, 0.0, 0.0], radius = 1.0 }";
        let mesh = "[[objects]]\nmesh = \"meshes/icosphere.obj\"\n";
        let first = format!("[[objects]]\n{sphere}\nmaterial = \"meshes/icosphere.obj:gold\"\n");
        // Either order compiles, to the same materials.
        let before = compile(&format!("{first}{mesh}")).unwrap_or_else(|e| panic!("{e}"));
        let after = compile(&format!("{mesh}{first}")).unwrap_or_else(|e| panic!("{e}"));
        let gold = Vec3::new(0.6, 0.45, 0.1);
        for scene in [&before, &after] {
            assert_eq!(
                scene.materials.iter().filter(|m| m.diffuse == gold).count(),
                1
            );
        }
        // A name the file does not have, or a file that is not there.
        let e = compile(&format!(
            "[[objects]]\n{sphere}\nmaterial = \"meshes/icosphere.obj:silver\"\n"
        ))
        .unwrap_err();
        assert_eq!(e.location, "objects[0].material", "{e}");
        assert!(e.message.contains("unknown material"), "{e}");
        let e = compile(&format!(
            "[[objects]]\n{sphere}\nmaterial = \"meshes/nothere.obj:gold\"\n"
        ))
        .unwrap_err();
        assert_eq!(e.location, "objects[0].material", "{e}");
        assert!(e.message.contains("cannot read"), "{e}");
    }

    fn first_vertex(text: &str) -> Vec3 {
        compiled(text).geometry.file_order_triangles()[0][0]
    }

    #[test]
    fn transforms_scale_then_rotate_then_translate_and_matrices_are_row_major() {
        let tri = "triangle = { v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] }";
        let p = first_vertex(&format!(
            "[[objects]]\n{tri}\ntransform = {{ scale = 2.0, rotate = [0.0, 0.0, 1.0, 90.0], translate = [10.0, 0.0, 0.0] }}"
        ));
        assert!((p - Vec3::new(10.0, 2.0, 0.0)).length() < 1e-5, "{p}");
        let p = first_vertex(&format!(
            "[[objects]]\n{tri}\ntransform = {{ matrix = [[1.0, 0.0, 0.0, 5.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]] }}"
        ));
        assert_eq!(p, Vec3::new(6.0, 0.0, 0.0));
        // A group's transform applies after its members' own.
        let p = first_vertex(&format!(
            "[[objects]]\ntransform = {{ translate = [0.0, 3.0, 0.0] }}\ngroup = [ {{ {tri}, transform = {{ scale = 2.0 }} }} ]"
        ));
        assert_eq!(p, Vec3::new(2.0, 3.0, 0.0));
        for (transform, key) in [
            ("{ matrix = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]], scale = 2.0 }", "objects[0].transform"),
            ("{ matrix = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [1.0, 0.0, 0.0, 1.0]] }", "objects[0].transform.matrix"),
            ("{ scale = [1.0, 0.0, 1.0] }", "objects[0].transform.scale"),
        ] {
            let e = rejected(&format!("[[objects]]\n{tri}\ntransform = {transform}"));
            assert_eq!(e.location, key, "{transform}: {e}");
        }
    }

    #[test]
    fn spheres_are_baked_under_similarities_and_keep_their_space_otherwise() {
        let s = compiled(
            r#"
[[objects]]
sphere = { center = [1.0, 0.0, 0.0], radius = 0.5 }
transform = { scale = 2.0, rotate = [0.0, 0.0, 1.0, 90.0], translate = [0.0, 0.0, 3.0] }
[[objects]]
sphere = { radius = 1.0 }
transform = { scale = [1.0, 2.0, 1.0] }
"#,
        );
        let [baked, kept] = [s.geometry.shapes[0], s.geometry.shapes[1]];
        assert_eq!(baked.transform, NO_TRANSFORM);
        let Shape::Sphere(b) = baked.shape else {
            panic!("{baked:?}")
        };
        assert!(
            (b.center - Vec3::new(0.0, 2.0, 3.0)).length() < 1e-5,
            "{b:?}"
        );
        assert!((b.radius - 1.0).abs() < 1e-6, "{b:?}");
        assert_ne!(
            kept.transform, NO_TRANSFORM,
            "an ellipsoid keeps its transform"
        );
        assert!(similarity_scale(&Affine3A::from_scale_rotation_translation(
            Vec3::splat(3.0),
            Quat::from_rotation_y(0.3),
            Vec3::ONE
        ))
        .is_some_and(|s| (s - 3.0).abs() < 1e-5));
        assert!(similarity_scale(&Affine3A::from_scale(Vec3::new(1.0, 1.0, 1.01))).is_none());
        let shear = Affine3A::from_cols_array(&[
            1.0, 0.0, 0.0, 0.5, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0,
        ]);
        assert!(similarity_scale(&shear).is_none());
    }

    #[test]
    fn groups_pass_their_material_down_unless_a_member_names_its_own() {
        let s = compiled(
            r#"
[materials.red]
diffuse = [0.7, 0.1, 0.1]
[materials.blue]
diffuse = [0.1, 0.1, 0.7]
[[objects]]
material = "red"
group = [ { sphere = { radius = 1.0 } }, { sphere = { radius = 2.0 }, material = "blue" } ]
"#,
        );
        let colour = |i: usize| s.materials[s.geometry.shapes[i].material as usize].diffuse;
        assert_eq!(colour(0), Vec3::new(0.7, 0.1, 0.1));
        assert_eq!(colour(1), Vec3::new(0.1, 0.1, 0.7));
    }

    #[test]
    fn an_object_needs_exactly_one_shape() {
        let e = rejected("[[objects]]\nmaterial = \"x\"");
        assert!(e.message.contains("needs one of"), "{e}");
        let e = rejected(
            "[[objects]]\nsphere = { radius = 1.0 }\nplane = { normal = [0.0, 1.0, 0.0] }",
        );
        assert!(e.message.contains("more than one shape"), "{e}");
        assert_eq!(e.location, "objects[0]");
    }
}
