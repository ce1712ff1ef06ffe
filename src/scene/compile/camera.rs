//! `[camera]`, or the camera a glTF file gives (see `import`), or the
//! default view.

use super::Compiler;
use crate::camera::{Camera, Orthographic, Perspective, ThinLens, View};
use crate::error::InputResult;
use crate::scene::description::{CameraDesc, CameraType};
use crate::scene::RenderSettings;

/// Vertical field of view of a camera that gives none, in degrees.
pub const DEFAULT_FOV: f32 = 40.0;
/// World-space view height of an orthographic camera that gives none.
pub const DEFAULT_HEIGHT: f32 = 4.0;

impl Compiler<'_> {
    pub(super) fn camera(
        &self,
        desc: Option<&CameraDesc>,
        s: &RenderSettings,
    ) -> InputResult<Camera> {
        let (w, h) = (s.width, s.height);
        let Some(d) = desc else {
            return self.camera(Some(&CameraDesc::default()), s);
        };
        let what = match d.kind {
            CameraType::Perspective => "a perspective camera",
            CameraType::Orthographic => "an orthographic camera",
            CameraType::ThinLens => "a thin_lens camera",
        };
        let given = [
            ("fov", d.fov.is_some()),
            ("aperture", d.aperture.is_some()),
            ("focus_distance", d.focus_distance.is_some()),
            ("height", d.height.is_some()),
        ];
        let takes: &[&str] = match d.kind {
            CameraType::Perspective => &["fov"],
            CameraType::Orthographic => &["height"],
            CameraType::ThinLens => &["fov", "aperture", "focus_distance"],
        };
        self.only("camera", what, &given, takes)?;
        let position = self.v3(d.position, "camera.position")?;
        let look_at = self.v3(d.look_at, "camera.look_at")?;
        let up = self.v3(d.up, "camera.up")?;
        let ends = ["camera.position", "camera.look_at"];
        if position == look_at {
            return Err(self.err_among(
                "camera.look_at",
                &ends[..1],
                "equals camera.position, so there is no view direction",
            ));
        }
        if !(look_at - position).length_squared().is_finite() {
            return Err(self.err_among(
                "camera.look_at",
                &ends[..1],
                "lies too far from camera.position for 32-bit floats (their distance must stay below about 1e19)",
            ));
        }
        let view = View::look_at(position, look_at, up, w, h).ok_or_else(|| {
            let message = if self.gives("camera.up") || !up.is_finite() {
                "is zero or parallel to the view direction".to_string()
            } else {
                // The user never wrote `up`: say which one was meant.
                format!(
                    "is not given, and its default {} is parallel to the view direction from camera.position to camera.look_at: give camera.up across it",
                    super::validate::written(up)
                )
            };
            self.err_among("camera.up", &ends, message)
        })?;
        let fov = |c: &Self| -> InputResult<f32> {
            let f = c.finite(d.fov.unwrap_or(DEFAULT_FOV), "camera.fov")?;
            if f > 0.0 && f < 180.0 {
                Ok(f)
            } else {
                Err(c.err(
                    "camera.fov",
                    format!("must be between 0 and 180 degrees, got {f}"),
                ))
            }
        };
        Ok(match d.kind {
            CameraType::Perspective => Camera::Perspective(Perspective::new(view, fov(self)?)),
            CameraType::Orthographic => Camera::Orthographic(Orthographic::new(
                view,
                self.positive(d.height.unwrap_or(DEFAULT_HEIGHT), "camera.height")?,
            )),
            CameraType::ThinLens => {
                let focus_distance = match d.focus_distance {
                    Some(f) => self.positive(f, "camera.focus_distance")?,
                    None => (look_at - position).length(),
                };
                Camera::ThinLens(ThinLens {
                    pinhole: Perspective::new(view, fov(self)?),
                    aperture: self.non_negative(d.aperture.unwrap_or(0.0), "camera.aperture")?,
                    focus_distance,
                })
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{compiled, rejected};
    use crate::camera::Camera;

    #[test]
    fn a_thin_lens_focuses_on_look_at_unless_told_otherwise() {
        let s = compiled(
            "[camera]\ntype = \"thin_lens\"\nposition = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 1.0]\naperture = 0.1\n",
        );
        let Camera::ThinLens(c) = s.camera else {
            panic!("{:?}", s.camera)
        };
        assert_eq!((c.focus_distance, c.aperture), (4.0, 0.1));
        let s = compiled("[camera]\ntype = \"thin_lens\"\nfocus_distance = 2.5\n");
        let Camera::ThinLens(c) = s.camera else {
            panic!("{:?}", s.camera)
        };
        assert_eq!(c.focus_distance, 2.5);
    }

    #[test]
    fn degenerate_views_and_fields_of_view_are_rejected() {
        for (text, key) in [
            (
                "[camera]\nposition = [1.0, 2.0, 3.0]\nlook_at = [1.0, 2.0, 3.0]",
                "camera.look_at",
            ),
            (
                "[camera]\nposition = [0.0, 5.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]",
                "camera.up",
            ),
            ("[camera]\nfov = 180.0", "camera.fov"),
            ("[camera]\nfov = 0.0", "camera.fov"),
            (
                "[camera]\ntype = \"orthographic\"\nheight = -1.0",
                "camera.height",
            ),
        ] {
            assert_eq!(rejected(text).location, key, "{text}");
        }
    }

    #[test]
    fn keys_a_camera_type_does_not_use_are_errors() {
        for (text, key, line, needle) in [
            (
                "[camera]\naperture = 0.1",
                "camera.aperture",
                2,
                "perspective camera, which takes fov",
            ),
            (
                "[camera]\ntype = \"orthographic\"\nfov = 30.0",
                "camera.fov",
                3,
                "which takes height",
            ),
            (
                "[camera]\ntype = \"thin_lens\"\nheight = 2.0",
                "camera.height",
                3,
                "fov, aperture and focus_distance",
            ),
        ] {
            let e = rejected(text);
            assert_eq!((e.location.as_str(), e.line), (key, Some(line)), "{text}");
            assert!(e.message.contains(needle), "{text}: {e}");
        }
    }
}
