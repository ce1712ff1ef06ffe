//! What a node contributes in world space: its local transform, a mesh
//! it alone uses with the world transform baked in (normals by the normal
//! matrix), and its camera and `KHR_lights_punctual` light.

use super::{Loader, LUMENS_PER_WATT};
use crate::error::InputResult;
use crate::scene::asset::{LoadedCamera, LoadedLight, LoadedMesh};
use ::gltf::json;
use glam::{Affine3A, Mat4, Quat, Vec3};
use json::validation::Checked;

impl Loader<'_> {
    pub(super) fn local_transform(&self, index: usize, node: &json::Node) -> InputResult<Mat4> {
        let matrix = match node.matrix {
            Some(m) => Mat4::from_cols_array(&m),
            None => {
                let translation = Vec3::from(node.translation.unwrap_or([0.0; 3]));
                let scale = Vec3::from(node.scale.unwrap_or([1.0; 3]));
                let rotation = Quat::from_array(
                    node.rotation
                        .as_ref()
                        .map(|q| q.0)
                        .unwrap_or([0.0, 0.0, 0.0, 1.0]),
                );
                let length = rotation.length();
                if !(length.is_finite() && length > 0.0) {
                    return Err(self.error(
                        format!("nodes[{index}].rotation"),
                        "rotation is not a usable quaternion (zero or not finite)",
                    ));
                }
                Mat4::from_scale_rotation_translation(scale, rotation / length, translation)
            }
        };
        if !matrix.is_finite() {
            return Err(self.error(
                format!("nodes[{index}]"),
                "transform has values that are not finite",
            ));
        }
        Ok(matrix)
    }

    /// Bake a node's world transform into a mesh read in local space
    /// ([`LoadedMesh::placed`]).
    pub(super) fn place(
        &self,
        node: usize,
        mesh: LoadedMesh,
        world: &Mat4,
    ) -> InputResult<LoadedMesh> {
        let mesh = mesh.placed(&Affine3A::from_mat4(*world));
        if mesh.positions.iter().any(|p| !p.is_finite()) {
            return Err(self.to_infinity(node, &mesh.name));
        }
        Ok(mesh)
    }

    pub(super) fn to_infinity(&self, node: usize, mesh: &str) -> crate::error::InputError {
        self.error(
            format!("nodes[{node}]"),
            format!("the node's transform takes positions of mesh '{mesh}' to infinity"),
        )
    }

    pub(super) fn camera(
        &self,
        node: usize,
        index: usize,
        world: &Mat4,
    ) -> InputResult<LoadedCamera> {
        use json::camera::Type;
        let location = format!("cameras[{index}]");
        let camera = self.root.cameras.get(index).ok_or_else(|| {
            self.error(
                format!("nodes[{node}].camera"),
                format!("{location} does not exist"),
            )
        })?;
        let (yfov_degrees, ortho_height, aspect_ratio) = match camera.type_ {
            Checked::Valid(Type::Perspective) => {
                let p = camera.perspective.as_ref().ok_or_else(|| {
                    self.error(
                        &location,
                        "type is perspective but there is no perspective object",
                    )
                })?;
                if !(p.yfov.is_finite() && p.yfov > 0.0 && p.yfov < std::f32::consts::PI) {
                    return Err(self.error(
                        format!("{location}.perspective.yfov"),
                        format!("yfov must be between 0 and π radians, found {}", p.yfov),
                    ));
                }
                // An unusable aspect ratio is left to the image size.
                let aspect = p.aspect_ratio.filter(|a| a.is_finite() && *a > 0.0);
                (Some(p.yfov.to_degrees()), None, aspect)
            }
            Checked::Valid(Type::Orthographic) => {
                let o = camera.orthographic.as_ref().ok_or_else(|| {
                    self.error(
                        &location,
                        "type is orthographic but there is no orthographic object",
                    )
                })?;
                if !(o.ymag.is_finite() && o.ymag > 0.0) {
                    return Err(self.error(
                        format!("{location}.orthographic.ymag"),
                        format!("ymag must be a positive number, found {}", o.ymag),
                    ));
                }
                let aspect = Some(o.xmag / o.ymag).filter(|a| a.is_finite() && *a > 0.0);
                (None, Some(2.0 * o.ymag), aspect)
            }
            Checked::Invalid => return Err(self.error(location, "invalid camera type")),
        };
        let forward = world.transform_vector3(-Vec3::Z).normalize_or_zero();
        let up = world.transform_vector3(Vec3::Y);
        let up = (up - forward * up.dot(forward)).normalize_or_zero();
        if forward == Vec3::ZERO || up == Vec3::ZERO {
            return Err(self.error(
                format!("nodes[{node}]"),
                "the camera's world transform is degenerate (zero scale?)",
            ));
        }
        Ok(LoadedCamera {
            position: world.transform_point3(Vec3::ZERO),
            forward,
            up,
            yfov_degrees,
            ortho_height,
            aspect_ratio,
        })
    }

    /// A node's `KHR_lights_punctual` light at the node's world origin,
    /// spot and directional lights shining along its world −Z. Candela
    /// (point, spot) become W/sr and lux (directional) W/m², both by the
    /// photometric constant: `color · intensity / 683`.
    pub(super) fn light(
        &self,
        node: usize,
        index: usize,
        world: &Mat4,
    ) -> InputResult<LoadedLight> {
        use json::extensions::scene::khr_lights_punctual::Type;
        let location = format!("extensions.KHR_lights_punctual.lights[{index}]");
        let light = self
            .root
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .and_then(|l| l.lights.get(index))
            .ok_or_else(|| {
                self.error(
                    format!("nodes[{node}].extensions.KHR_lights_punctual"),
                    format!("{location} does not exist"),
                )
            })?;
        let kind = match light.type_ {
            Checked::Valid(kind) => kind,
            Checked::Invalid => return Err(self.error(location, "invalid light type")),
        };
        let intensity = Vec3::from(light.color) * light.intensity / LUMENS_PER_WATT;
        if !intensity.is_finite() || intensity.min_element() < 0.0 {
            return Err(self.error(
                location,
                "color and intensity must be finite and not negative",
            ));
        }
        let position = world.transform_point3(Vec3::ZERO);
        let direction = world.transform_vector3(-Vec3::Z).normalize_or_zero();
        if kind != Type::Point && direction == Vec3::ZERO {
            return Err(self.error(
                format!("nodes[{node}]"),
                "the light's world transform is degenerate (zero scale?)",
            ));
        }
        Ok(match kind {
            Type::Point => LoadedLight::Point {
                position,
                intensity,
            },
            Type::Directional => LoadedLight::Directional {
                direction,
                irradiance: intensity,
            },
            Type::Spot => {
                use std::f32::consts::{FRAC_PI_2, FRAC_PI_4};
                // The validator insists on `spot`; glTF's defaults else.
                let (inner, outer) = light.spot.as_ref().map_or((0.0, FRAC_PI_4), |s| {
                    (s.inner_cone_angle, s.outer_cone_angle)
                });
                let right = FRAC_PI_2;
                if !(outer > 0.0 && outer <= right && inner >= 0.0 && inner <= outer) {
                    return Err(self.error(
                        format!("{location}.spot"),
                        format!(
                            "cone angles must satisfy 0 ≤ innerConeAngle ≤ outerConeAngle ≤ π/2 \
                             and outerConeAngle > 0, found {inner} and {outer}"
                        ),
                    ));
                }
                LoadedLight::Spot {
                    position,
                    direction,
                    intensity,
                    inner_angle: inner,
                    outer_angle: outer,
                }
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::*;
    use crate::scene::asset::LoadedLight;

    #[test]
    fn node_transforms_are_baked_into_positions() {
        let b = triangle_builder();
        let s = std::f32::consts::FRAC_1_SQRT_2;
        let rest = format!(
            r#"{TRIANGLE_MESH},"scene":0,"scenes":[{{"nodes":[0,1,2,3,4]}}],"nodes":[
                {{"mesh":0,"translation":[1,2,3]}},
                {{"mesh":0,"rotation":[0,0,{s},{s}]}},
                {{"mesh":0,"scale":[2,3,4]}},
                {{"mesh":0,"matrix":[2,0,0,0, 0,2,0,0, 0,0,2,0, 10,0,0,1]}},
                {{"translation":[0,0,5],"scale":[2,2,2],"children":[5]}},
                {{"mesh":0,"translation":[1,0,0]}}
            ]"#
        );
        let asset = load_baked(&b, &rest);
        assert_eq!(asset.meshes.len(), 5);
        assert!(asset.meshes.iter().all(|m| m.name == "tri"));
        assert_corners(&asset.meshes[0], [[1., 2., 3.], [2., 2., 3.], [1., 3., 3.]]);
        assert_corners(
            &asset.meshes[1],
            [[0., 0., 0.], [0., 1., 0.], [-1., 0., 0.]],
        );
        assert_corners(&asset.meshes[2], [[0., 0., 0.], [2., 0., 0.], [0., 3., 0.]]);
        assert_corners(
            &asset.meshes[3],
            [[10., 0., 0.], [12., 0., 0.], [10., 2., 0.]],
        );
        // Parent T(0,0,5)·S(2) applied after the child's T(1,0,0).
        assert_corners(&asset.meshes[4], [[2., 0., 5.], [4., 0., 5.], [2., 2., 5.]]);
        assert_eq!(asset.triangle_count(), 5);
    }

    #[test]
    fn cameras_and_lights_are_placed_in_world_space() {
        let b = triangle_builder();
        let s = std::f32::consts::FRAC_1_SQRT_2;
        let rest = format!(
            r#"{TRIANGLE_MESH},"scenes":[{{"nodes":[0,2,4]}}],
            "cameras":[{{"type":"perspective","perspective":{{"yfov":0.5,"znear":0.1}}}},
                       {{"type":"orthographic","orthographic":{{"xmag":4,"ymag":3,"znear":0.1,"zfar":100}}}}],
            "extensions":{{"KHR_lights_punctual":{{"lights":[
                {{"type":"point","color":[1,0.5,0.25],"intensity":683}},
                {{"type":"spot","spot":{{}}}},
                {{"type":"directional"}}]}}}},
            "nodes":[
                {{"translation":[0,1,0],"children":[1]}},
                {{"camera":0,"translation":[0,0,5],"rotation":[0,{s},0,{s}]}},
                {{"camera":1,"extensions":{{"KHR_lights_punctual":{{"light":0}}}},"translation":[3,4,5]}},
                {{"extensions":{{"KHR_lights_punctual":{{"light":1}}}}}},
                {{"children":[3,5]}},
                {{"extensions":{{"KHR_lights_punctual":{{"light":2}}}}}}
            ]"#
        );
        let asset = load_json(&b, &rest).unwrap();
        assert_eq!(asset.cameras.len(), 2);
        let perspective = &asset.cameras[0];
        assert_close(perspective.position, Vec3::new(0., 1., 5.));
        // A quarter turn about +Y takes −Z to −X.
        assert_close(perspective.forward, Vec3::new(-1., 0., 0.));
        assert_close(perspective.up, Vec3::Y);
        assert!((perspective.yfov_degrees.unwrap() - 0.5f32.to_degrees()).abs() < 1e-4);
        assert_eq!(perspective.ortho_height, None);
        let ortho = &asset.cameras[1];
        assert_close(ortho.position, Vec3::new(3., 4., 5.));
        assert_close(ortho.forward, -Vec3::Z);
        assert_eq!(ortho.ortho_height, Some(6.0));
        assert_eq!(ortho.yfov_degrees, None);

        assert_eq!(perspective.aspect_ratio, None);
        assert_eq!(ortho.aspect_ratio, Some(4.0 / 3.0));

        let [LoadedLight::Point {
            position,
            intensity,
        }, LoadedLight::Spot {
            position: spot_at,
            direction: spot_axis,
            intensity: spot_intensity,
            inner_angle,
            outer_angle,
        }, LoadedLight::Directional {
            direction,
            irradiance,
        }] = asset.lights[..]
        else {
            panic!("{:?}", asset.lights);
        };
        assert_close(position, Vec3::new(3., 4., 5.));
        assert_close(intensity, Vec3::new(1.0, 0.5, 0.25));
        // Spot and directional lights shine along their node's −Z; glTF's
        // defaults: intensity 1 (candela or lux), cone angles 0 and π/4.
        assert_close(spot_at, Vec3::ZERO);
        assert_close(spot_axis, -Vec3::Z);
        assert_close(spot_intensity, Vec3::splat(1.0 / 683.0));
        assert_eq!(
            (inner_angle, outer_angle),
            (0.0, std::f32::consts::FRAC_PI_4)
        );
        assert_close(direction, -Vec3::Z);
        assert_close(irradiance, Vec3::splat(1.0 / 683.0));
    }

    #[test]
    fn spot_and_directional_lights_turn_with_their_node_and_check_their_cones() {
        let b = triangle_builder();
        let s = std::f32::consts::FRAC_1_SQRT_2;
        let lights = r#""extensions":{"KHR_lights_punctual":{"lights":[
                {"type":"spot","color":[1,1,1],"intensity":1366,"spot":{"innerConeAngle":0.25,"outerConeAngle":0.5}},
                {"type":"directional","color":[0,1,0],"intensity":683}]}}"#;
        let rest = format!(
            r#"{TRIANGLE_MESH},{lights},"nodes":[
                {{"rotation":[-{s},0,0,{s}],"translation":[0,5,0],"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}},
                {{"rotation":[0,{s},0,{s}],"extensions":{{"KHR_lights_punctual":{{"light":1}}}}}}]"#
        );
        let asset = load_json(&b, &rest).unwrap();
        let LoadedLight::Spot {
            position,
            direction,
            intensity,
            inner_angle,
            outer_angle,
        } = asset.lights[0]
        else {
            panic!("{:?}", asset.lights);
        };
        // A quarter turn about −X takes −Z to −Y: the spot points down.
        assert_close(position, Vec3::new(0., 5., 0.));
        assert_close(direction, -Vec3::Y);
        assert_close(intensity, Vec3::splat(2.0));
        assert_eq!((inner_angle, outer_angle), (0.25, 0.5));
        let LoadedLight::Directional {
            direction,
            irradiance,
        } = asset.lights[1]
        else {
            panic!("{:?}", asset.lights);
        };
        assert_close(direction, -Vec3::X);
        assert_close(irradiance, Vec3::Y);
        for spot in [
            r#"{"innerConeAngle":0.6,"outerConeAngle":0.5}"#,
            r#"{"outerConeAngle":2}"#,
            r#"{"outerConeAngle":0}"#,
        ] {
            let rest = format!(
                r#"{TRIANGLE_MESH},"extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"spot","spot":{spot}}}]}}}},
                "nodes":[{{"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}}]"#
            );
            expect_error(
                load_json(&b, &rest),
                "scene.gltf",
                "extensions.KHR_lights_punctual.lights[0].spot",
                "cone angles",
            );
        }
    }

    #[test]
    fn normals_use_the_inverse_transpose() {
        let mut b = Builder::default();
        b.positions(&TRIANGLE);
        let s = std::f32::consts::FRAC_1_SQRT_2;
        b.vec3(&[[s, s, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]], false);
        let rest = r#""meshes":[{"primitives":[{"attributes":{"POSITION":0,"NORMAL":1}}]}],
            "nodes":[{"mesh":0,"scale":[2,1,1]},{"mesh":0,"scale":[-1,1,1]},{"mesh":0}]"#;
        let asset = load_baked(&b, rest);
        let normals = |m: usize| asset.meshes[m].normals.clone().expect("normals");
        let stretched = normals(0);
        assert_close(stretched.values[0], Vec3::new(0.5, 1.0, 0.0).normalize());
        assert_close(stretched.values[1], Vec3::X);
        assert_eq!(stretched.indices, asset.meshes[0].indices);
        let mirrored = normals(1);
        assert_close(mirrored.values[1], -Vec3::X);
        assert_close(mirrored.values[2], Vec3::Z);
        assert_eq!(
            asset.meshes[1].indices,
            vec![[0, 1, 2]],
            "winding kept as stored"
        );
        assert_close(asset.meshes[1].positions[1], -Vec3::X);
        let mirrored: Vec<bool> = asset.meshes.iter().map(|m| m.mirrored).collect();
        assert_eq!(
            mirrored,
            [false, true, false],
            "the mirroring node marks its copy"
        );
        assert_close(normals(2).values[0], Vec3::new(s, s, 0.0));
    }

    #[test]
    fn non_finite_positions_are_refused() {
        let mut b = Builder::default();
        b.vec3(
            &[[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]],
            false,
        );
        let rest =
            r#""meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}]"#;
        expect_error(
            load_json(&b, rest),
            "scene.gltf",
            "accessors[0]",
            "not finite",
        );
        let b = triangle_builder();
        let rest = format!(
            r#"{TRIANGLE_MESH},"nodes":[{{"mesh":0,"scale":[1e30,1,1],"children":[1]}},{{"mesh":0,"scale":[1e30,1,1]}}]"#
        );
        expect_error(
            load_json(&b, &rest),
            "scene.gltf",
            "nodes[1]",
            "world transform is not finite",
        );
        // A finite transform can still take a vertex to infinity.
        let rest = format!(
            r#"{TRIANGLE_MESH},"nodes":[{{"mesh":0,"scale":[3e38,1,1],"translation":[3e38,0,0]}}]"#
        );
        expect_error(
            load_json(&b, &rest),
            "scene.gltf",
            "nodes[0]",
            "to infinity",
        );
        let rest = format!(r#"{TRIANGLE_MESH},"nodes":[{{"mesh":0,"translation":[1e39,0,0]}}]"#);
        expect_error(load_json(&b, &rest), "scene.gltf", "nodes[0]", "not finite");
    }
}
