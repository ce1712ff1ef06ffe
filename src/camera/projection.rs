//! The camera as matrices, for the standard OpenEXR attributes
//! `worldToCamera` and `worldToNDC` (ImfStandardAttributes.h): camera space
//! is left-handed with +x right, +y up and +z the viewing direction; NDC
//! has (0, 0) at the top-left and (1, 1) at the bottom-right corner of the
//! display window, and a world point maps to it by the homogeneous product
//! followed by the division by w. The matrices here act on column vectors
//! (glam's convention); OpenEXR stores the transpose, which is exactly
//! glam's column-major array.

use super::{Camera, View};
use glam::{Mat4, Vec4};

impl View {
    /// World to camera space (+x right, +y up, +z forward).
    pub fn world_to_camera(&self) -> Mat4 {
        let (r, u, f, p) = (self.right, self.up, self.forward, self.position);
        Mat4::from_cols(
            Vec4::new(r.x, u.x, f.x, 0.0),
            Vec4::new(r.y, u.y, f.y, 0.0),
            Vec4::new(r.z, u.z, f.z, 0.0),
            Vec4::new(-r.dot(p), -u.dot(p), -f.dot(p), 1.0),
        )
    }
}

impl Camera {
    /// World to camera space; see [`View::world_to_camera`].
    pub fn world_to_camera(&self) -> Mat4 {
        self.view().world_to_camera()
    }

    /// World to normalized device coordinates of the whole image: x right
    /// and y down in [0, 1], after division by w. A thin lens projects like
    /// its pinhole (the centre of the lens).
    pub fn world_to_ndc(&self) -> Mat4 {
        let view = self.view();
        let a = view.aspect();
        // Camera space to NDC: screen s = (x, y)/z/tan(fov/2) in
        // [-aspect, aspect] × [-1, 1] (y up); NDC = ((s.x/a + 1)/2, (1 - s.y)/2).
        let camera_to_ndc = match self {
            Camera::Perspective(c) => perspective(c.tan_half_fov, a),
            Camera::ThinLens(c) => perspective(c.pinhole.tan_half_fov, a),
            Camera::Orthographic(c) => {
                let h = c.half_height;
                Mat4::from_cols(
                    Vec4::new(0.5 / (h * a), 0.0, 0.0, 0.0),
                    Vec4::new(0.0, -0.5 / h, 0.0, 0.0),
                    Vec4::new(0.0, 0.0, 1.0, 0.0),
                    Vec4::new(0.5, 0.5, 0.0, 1.0),
                )
            }
        };
        camera_to_ndc * view.world_to_camera()
    }
}

/// Camera space to homogeneous NDC for a pinhole of half-height `t` (the
/// tangent of half the vertical field of view) and aspect `a`: w = z.
fn perspective(t: f32, a: f32) -> Mat4 {
    Mat4::from_cols(
        Vec4::new(0.5 / (t * a), 0.0, 0.0, 0.0),
        Vec4::new(0.0, -0.5 / t, 0.0, 0.0),
        Vec4::new(0.5, 0.5, 1.0, 1.0),
        Vec4::new(0.0, 0.0, 0.0, 0.0),
    )
}

#[cfg(test)]
mod tests {
    use super::super::{Orthographic, Perspective, ThinLens};
    use super::*;
    use glam::{Vec2, Vec3};

    fn view() -> View {
        View::look_at(
            Vec3::new(1.0, 2.0, 5.0),
            Vec3::new(0.0, 0.5, 0.0),
            Vec3::Y,
            64,
            48,
        )
        .unwrap()
    }

    /// A point on the ray through a film position projects back to that
    /// position over the image size, for every camera.
    #[test]
    fn points_on_camera_rays_project_to_their_film_position() {
        let cameras = [
            Camera::Perspective(Perspective::new(view(), 40.0)),
            Camera::Orthographic(Orthographic::new(view(), 3.0)),
            Camera::ThinLens(ThinLens {
                pinhole: Perspective::new(view(), 60.0),
                aperture: 0.2,
                focus_distance: 4.0,
            }),
        ];
        for camera in cameras {
            let m = camera.world_to_ndc();
            for film in [
                Vec2::new(0.5, 0.5),
                Vec2::new(32.0, 24.0),
                Vec2::new(63.0, 7.25),
            ] {
                // The lens centre: the pinhole ray.
                let ray = camera.generate_ray(film, Vec2::splat(0.5));
                let p = ray.at(3.0);
                let h = m * p.extend(1.0);
                let ndc = Vec2::new(h.x / h.w, h.y / h.w);
                let expected = film / Vec2::new(64.0, 48.0);
                assert!((ndc - expected).length() < 1e-4, "{camera:?} {film}: {ndc}");
                let c = camera.world_to_camera() * p.extend(1.0);
                assert!(c.z > 0.0, "in front of the camera: +z forward");
            }
        }
    }

    #[test]
    fn camera_space_is_right_up_forward() {
        let v = view();
        let m = v.world_to_camera();
        let at = |p: Vec3| (m * p.extend(1.0)).truncate();
        assert!(at(v.position).length() < 1e-6);
        assert!((at(v.position + v.right) - Vec3::X).length() < 1e-5);
        assert!((at(v.position + v.up) - Vec3::Y).length() < 1e-5);
        assert!((at(v.position + v.forward) - Vec3::Z).length() < 1e-5);
    }
}
