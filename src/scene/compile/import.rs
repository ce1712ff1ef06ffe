//! What a mesh file brings besides its triangles: a glTF file's lights and
//! cameras, placed by the object's transform.
//!
//! ```toml
//! [[objects]]
//! mesh = "room.glb"
//! lights = false   # leave the file's KHR_lights_punctual lights out (default: in)
//! camera = 1       # the file's camera 1 is the scene's camera
//! ```
//!
//! Without `camera`, and without a `[camera]` table, the first camera of
//! the first mesh file that has one is used, else the default view. Each
//! light and camera becomes the `[[lights]]` entry or `[camera]` table that
//! a scene file would write for it ([`LoadedLight::to_desc`],
//! [`LoadedCamera::to_desc`]), so they are checked and compiled as those
//! are, and `strata render model.glb --save-scene` can write them out.
//!
//! [`LoadedLight::to_desc`]: crate::scene::asset::LoadedLight::to_desc
//! [`LoadedCamera::to_desc`]: crate::scene::asset::LoadedCamera::to_desc

use super::Compiler;
use crate::camera::Camera;
use crate::error::InputResult;
use crate::math::Transform;
use crate::scene::asset::LoadedCamera;
use crate::scene::description::{CameraDesc, ObjectDesc};
use crate::scene::RenderSettings;
use glam::Affine3A;

impl Compiler<'_> {
    /// The lights and cameras of mesh object `obj` (at key path `key`,
    /// placed by `m`), as its `lights` and `camera` keys say.
    pub(super) fn mesh_imports(
        &mut self,
        obj: &ObjectDesc,
        file: &str,
        key: &str,
        m: Affine3A,
    ) -> InputResult<()> {
        let (asset, _, _) = self.asset(file, &format!("{key}.mesh"))?;
        let t = Transform::new(m).expect("checked by placement");
        if obj.lights.unwrap_or(true) {
            for light in &asset.lights {
                self.light(&light.transformed(&t).to_desc(), &format!("{key}.mesh"))?;
            }
        }
        let cameras: Vec<LoadedCamera> = asset.cameras.iter().map(|c| c.transformed(&t)).collect();
        if let Some(n) = obj.camera {
            let at = format!("{key}.camera");
            let camera = cameras.get(n).ok_or_else(|| {
                let has = match cameras.len() {
                    0 => "no cameras".to_string(),
                    1 => "one camera, camera 0".to_string(),
                    k => format!("{k} cameras, 0 to {}", k - 1),
                };
                self.err(
                    &at,
                    format!("'{file}' has {has}, so there is no camera {n}"),
                )
            })?;
            if let Some((_, earlier)) = &self.chosen_camera {
                return Err(self.err(
                    &at,
                    format!("{earlier} already chooses the scene's camera; give one `camera`"),
                ));
            }
            self.chosen_camera = Some((camera.to_desc(), at));
        }
        self.loaded_cameras.extend(cameras);
        Ok(())
    }

    /// Refuse `lights` and `camera` on an object whose shape brings none:
    /// keys that would silently do nothing. `what` says which ("a sphere",
    /// "a CSG operand").
    pub(super) fn no_imports(&self, obj: &ObjectDesc, key: &str, what: &str) -> InputResult<()> {
        let given = [
            ("lights", obj.lights.is_some()),
            ("camera", obj.camera.is_some()),
        ];
        match given.iter().find(|(_, set)| *set) {
            Some((name, _)) => Err(self.err(
                &format!("{key}.{name}"),
                format!("takes a mesh file's own {name}, which {what} does not have"),
            )),
            None => Ok(()),
        }
    }

    /// The scene's camera: the `[camera]` table, or the mesh file camera an
    /// object chose (not both), or the first mesh file camera, or the
    /// default view.
    pub(super) fn scene_camera(
        &self,
        table: Option<&CameraDesc>,
        s: &RenderSettings,
    ) -> InputResult<Camera> {
        match (table, &self.chosen_camera) {
            (Some(_), Some((_, at))) => Err(self.err(
                at,
                "chooses the scene's camera, but the scene has a [camera] table too; give one",
            )),
            (Some(d), None) | (None, Some((d, _))) => self.camera(Some(d), s),
            (None, None) => {
                let first = self.loaded_cameras.first().map(LoadedCamera::to_desc);
                self.camera(Some(first.as_ref().unwrap_or(&CameraDesc::default())), s)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::camera::Camera;
    use crate::light::Light;
    use crate::scene::loaders::test_files::{temp_dir, write};
    use crate::scene::{scene_from_str, RenderOverrides};
    use glam::Vec3;

    /// A one-triangle glTF with two cameras, a spot light and a point light.
    const GLTF: &str = r#"{"asset":{"version":"2.0"},
        "buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
        "bufferViews":[{"buffer":0,"byteLength":36}],
        "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
        "cameras":[{"type":"perspective","perspective":{"yfov":0.5,"znear":0.1}},
                   {"type":"orthographic","orthographic":{"xmag":2,"ymag":1.5,"znear":0.1,"zfar":9}}],
        "extensions":{"KHR_lights_punctual":{"lights":[
            {"type":"spot","intensity":683,"spot":{"innerConeAngle":0.2,"outerConeAngle":0.4}},
            {"type":"point","intensity":1366}]}},
        "nodes":[{"mesh":0},{"camera":0,"translation":[0,0,5]},{"camera":1,"translation":[0,0,7]},
                 {"translation":[0,3,0],"extensions":{"KHR_lights_punctual":{"light":0}}},
                 {"translation":[1,3,0],"extensions":{"KHR_lights_punctual":{"light":1}}}]}"#;

    fn scene(text: &str) -> Result<crate::scene::Scene, crate::error::InputError> {
        let dir = temp_dir("imports");
        write(&dir, "m.gltf", GLTF.as_bytes());
        scene_from_str(text, &dir.join("s.toml"), &RenderOverrides::default())
    }

    #[test]
    fn a_mesh_brings_its_lights_moved_unless_told_not_to() {
        let s = scene("[[objects]]\nmesh = \"m.gltf\"\ntransform = { translate = [10, 0, 0] }\n")
            .unwrap();
        assert_eq!(s.lights.len(), 2);
        let Light::Spot {
            position,
            direction,
            intensity,
            cos_inner,
            cos_outer,
        } = s.lights[0]
        else {
            panic!("{:?}", s.lights);
        };
        assert_eq!((position, direction), (Vec3::new(10.0, 3.0, 0.0), -Vec3::Z));
        assert_eq!(intensity, Vec3::ONE);
        assert!((cos_inner - 0.2f32.cos()).abs() < 1e-6 && (cos_outer - 0.4f32.cos()).abs() < 1e-6);
        assert!(matches!(s.lights[1], Light::Point { position, intensity }
            if position == Vec3::new(11.0, 3.0, 0.0) && intensity == Vec3::splat(2.0)));
        let s = scene("[[objects]]\nmesh = \"m.gltf\"\nlights = false\n").unwrap();
        assert!(s.lights.is_empty());
    }

    #[test]
    fn camera_picks_one_of_the_files_cameras_and_says_how_many_there_are() {
        // Without a choice, the first; with one, that one.
        let first = scene("[[objects]]\nmesh = \"m.gltf\"\n").unwrap();
        assert!(matches!(first.camera, Camera::Perspective(_)));
        let chosen = scene("[[objects]]\nmesh = \"m.gltf\"\ncamera = 1\n").unwrap();
        assert!(matches!(chosen.camera, Camera::Orthographic(_)));
        for (text, at, needle) in [
            ("[[objects]]\nmesh = \"m.gltf\"\ncamera = 2\n", "objects[0].camera", "has 2 cameras, 0 to 1, so there is no camera 2"),
            ("[camera]\nfov = 30\n[[objects]]\nmesh = \"m.gltf\"\ncamera = 0\n", "objects[0].camera", "[camera] table too"),
            ("[[objects]]\nmesh = \"m.gltf\"\ncamera = 0\n[[objects]]\nmesh = \"m.gltf\"\ncamera = 1\n", "objects[1].camera", "objects[0].camera already chooses"),
            ("[[objects]]\nsphere = { radius = 1 }\nlights = true\n", "objects[0].lights", "which a sphere does not have"),
            ("[[objects]]\ncsg = { op = \"union\", a = { mesh = \"m.gltf\", camera = 0 }, b = { sphere = { radius = 1 } } }\n", "objects[0].csg.a.camera", "CSG operand"),
        ] {
            let e = scene(text).unwrap_err();
            assert_eq!(e.location, at, "{text}: {e}");
            assert!(e.message.contains(needle), "{text}: {e}");
        }
    }
}
