//! Eight camera rays at once: [`Camera::generate_ray`] in `wide::f32x8`
//! lanes, for the samples of one batch (one pixel's pixel and lens
//! samples).
//!
//! A camera ray is a short chain of dependent divisions and square roots
//! (a thin lens's two normalisations and its focus distance); eight lanes
//! run eight chains at once, and the rays are built where the batch keeps
//! them rather than returned one by one through memory. Every lane does
//! the scalar code's operations in its order ([`Lanes3`] is glam's `Vec3`
//! arithmetic, the concentric disk's cosine and sine are the same libm
//! calls), so each ray is bit for bit the one
//! [`Camera::generate_ray`] makes; the tests check that for every camera.

use super::{Camera, View};
use crate::math::lanes::{Lanes3, LANES};
use crate::math::Ray;
use glam::Vec2;
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4};
use wide::f32x8;

/// Eight 2D points as two lanes.
fn split(points: &[Vec2; LANES]) -> (f32x8, f32x8) {
    (
        f32x8::new(points.map(|p| p.x)),
        f32x8::new(points.map(|p| p.y)),
    )
}

impl View {
    /// [`View::screen`] in lanes.
    #[inline]
    fn screen_lanes(&self, film: &[Vec2; LANES]) -> (f32x8, f32x8) {
        let (fx, fy) = split(film);
        let (w, h) = (self.width as f32, self.height as f32);
        let two = f32x8::splat(2.0);
        let x = (two * fx / f32x8::splat(w) - f32x8::ONE) * f32x8::splat(self.aspect());
        let y = f32x8::ONE - two * fy / f32x8::splat(h);
        (x, y)
    }

    /// `position + a·right + b·up` in lanes.
    #[inline]
    fn in_plane(&self, a: f32x8, b: f32x8) -> Lanes3 {
        Lanes3::splat(self.position)
            .add_scaled(a, Lanes3::splat(self.right))
            .add_scaled(b, Lanes3::splat(self.up))
    }
}

/// [`crate::sampling::warp::concentric_disk`] in lanes.
#[inline]
fn concentric_disk(u: &[Vec2; LANES]) -> (f32x8, f32x8) {
    let (ux, uy) = split(u);
    let two = f32x8::splat(2.0);
    let (ax, ay) = (two * ux - f32x8::ONE, two * uy - f32x8::ONE);
    let wide = ax.abs().simd_gt(ay.abs());
    let x_wedge = f32x8::splat(FRAC_PI_4) * (ay / ax);
    let y_wedge = f32x8::splat(FRAC_PI_2) - f32x8::splat(FRAC_PI_4) * (ax / ay);
    let r = wide.select(ax, ay);
    let theta = wide.select(x_wedge, y_wedge).to_array();
    // The scalar code's libm calls, lane by lane.
    let cos = f32x8::new(theta.map(f32::cos));
    let sin = f32x8::new(theta.map(f32::sin));
    let centre = ax.simd_eq(f32x8::ZERO) & ay.simd_eq(f32x8::ZERO);
    (
        centre.select(f32x8::ZERO, r * cos),
        centre.select(f32x8::ZERO, r * sin),
    )
}

/// Rays from lanes of origins and directions.
fn rays(origin: Lanes3, direction: Lanes3) -> [Ray; LANES] {
    let (origin, direction) = (origin.to_vecs(), direction.to_vecs());
    std::array::from_fn(|i| Ray::new(origin[i], direction[i]))
}

impl Camera {
    /// `self.generate_ray(film[i], lens[i])` for each lane `i`, bit for bit.
    pub fn generate_rays(&self, film: &[Vec2; LANES], lens: &[Vec2; LANES]) -> [Ray; LANES] {
        match self {
            Camera::Orthographic(c) => {
                let (sx, sy) = c.view.screen_lanes(film);
                let half = f32x8::splat(c.half_height);
                let origin = c.view.in_plane(sx * half, sy * half);
                rays(origin, Lanes3::splat(c.view.forward))
            }
            Camera::Perspective(c) => {
                let view = &c.view;
                rays(Lanes3::splat(view.position), pinhole_directions(c, film))
            }
            Camera::ThinLens(c) => {
                let view = &c.pinhole.view;
                let direction = pinhole_directions(&c.pinhole, film);
                if c.aperture <= 0.0 {
                    return rays(Lanes3::splat(view.position), direction);
                }
                // Where each pinhole ray meets the plane of focus.
                let forward = Lanes3::splat(view.forward);
                let t_focus = f32x8::splat(c.focus_distance) / direction.dot(forward);
                let focus = Lanes3::splat(view.position).add_scaled(t_focus, direction);
                let (dx, dy) = concentric_disk(lens);
                let aperture = f32x8::splat(c.aperture);
                let origin = view.in_plane(dx * aperture, dy * aperture);
                rays(origin, (focus - origin).normalize())
            }
        }
    }
}

/// [`super::Perspective::direction`] in lanes.
#[inline]
fn pinhole_directions(c: &super::Perspective, film: &[Vec2; LANES]) -> Lanes3 {
    let view = &c.view;
    let (sx, sy) = view.screen_lanes(film);
    let tan = f32x8::splat(c.tan_half_fov);
    Lanes3::splat(view.forward)
        .add_scaled(sx * tan, Lanes3::splat(view.right))
        .add_scaled(sy * tan, Lanes3::splat(view.up))
        .normalize()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Orthographic, Perspective, ThinLens};
    use crate::sampling::stream::{seeded, Draw};
    use glam::Vec3;

    fn cameras() -> Vec<Camera> {
        let view = View::look_at(
            Vec3::new(0.3, 1.6, 7.0),
            Vec3::new(0.0, 0.8, 0.1),
            Vec3::Y,
            200,
            150,
        )
        .expect("a view");
        let pinhole = Perspective::new(view, 40.0);
        vec![
            Camera::Orthographic(Orthographic::new(view, 3.0)),
            Camera::Perspective(pinhole),
            Camera::ThinLens(ThinLens {
                pinhole,
                aperture: 0.12,
                focus_distance: 7.1,
            }),
            Camera::ThinLens(ThinLens {
                pinhole,
                aperture: 0.0,
                focus_distance: 7.1,
            }),
        ]
    }

    /// Every camera's lanes against its scalar rays, on random film and
    /// lens points and on the lens's centre, axes and diagonals, where the
    /// concentric disk changes wedge or divides zero by zero.
    #[test]
    fn lanes_are_the_scalar_rays_bit_for_bit() {
        let mut rng = seeded(11);
        let special = [0.5f32, 0.0, 0.25, 0.75, 0.999_999_9];
        for camera in cameras() {
            for round in 0..2000 {
                let film: [Vec2; LANES] = std::array::from_fn(|_| {
                    Vec2::new(rng.range(0.0, 200.0), rng.range(0.0, 150.0))
                });
                let lens: [Vec2; LANES] = std::array::from_fn(|i| {
                    if round % 3 == 0 {
                        let (a, b) = (special[i % 5], special[(i + round) % 5]);
                        Vec2::new(a, if i % 2 == 0 { a } else { b })
                    } else {
                        Vec2::new(rng.unit(), rng.unit())
                    }
                });
                let lanes = camera.generate_rays(&film, &lens);
                for i in 0..LANES {
                    let want = camera.generate_ray(film[i], lens[i]);
                    let bits = |r: &Ray| {
                        (
                            r.origin.to_array().map(f32::to_bits),
                            r.direction.to_array().map(f32::to_bits),
                        )
                    };
                    assert_eq!(
                        bits(&lanes[i]),
                        bits(&want),
                        "{camera:?} {:?} {:?}",
                        film[i],
                        lens[i]
                    );
                    assert_eq!((lanes[i].tmin, lanes[i].tmax), (want.tmin, want.tmax));
                }
            }
        }
    }
}
