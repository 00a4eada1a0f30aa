//! The path tracer's BSDF at a surface point: Lambertian, or Lambertian plus the normalised
//! modified Phong lobe a material opts into ([`crate::scene::Phong`]). For a Lambertian
//! material every number is computed as the Lambertian-only tracer computed it, so the
//! references of Lambertian scenes keep their bytes.

use crate::sampling::{cosine_hemisphere, orthonormal_basis};
use crate::scene::Phong;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

pub(crate) struct Bsdf {
    diffuse: Vec3,
    /// rho_d / pi, the whole of f for a Lambertian surface.
    diffuse_f: Vec3,
    lobe: Option<Lobe>,
    /// The shading normal, on the side the path came from.
    normal: Vec3,
}

struct Lobe {
    specular: Vec3,
    exponent: f32,
    /// wo reflected about the normal: the lobe's axis.
    mirror: Vec3,
    /// The chance of sampling the lobe rather than the cosine (by luminance).
    chance: f32,
}

fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

impl Bsdf {
    pub(crate) fn new(diffuse: Vec3, phong: Option<&Phong>, normal: Vec3, wo: Vec3) -> Bsdf {
        let lobe = phong.filter(|p| p.specular.max_element() > 0.0).map(|p| Lobe {
            specular: p.specular,
            exponent: p.exponent,
            mirror: 2.0 * normal.dot(wo) * normal - wo,
            chance: luminance(p.specular) / (luminance(p.specular) + luminance(diffuse)).max(f32::MIN_POSITIVE),
        });
        Bsdf { diffuse, diffuse_f: diffuse * (1.0 / PI), lobe, normal }
    }

    /// f(wo, wi).
    pub(crate) fn eval(&self, wi: Vec3) -> Vec3 {
        match &self.lobe {
            None => self.diffuse_f,
            Some(l) => self.diffuse_f + l.specular * ((l.exponent + 2.0) / (2.0 * PI) * wi.dot(l.mirror).max(0.0).powf(l.exponent)),
        }
    }

    /// The solid-angle density with which [`Bsdf::sample`] picks `wi`.
    pub(crate) fn pdf(&self, wi: Vec3) -> f32 {
        let cosine = self.normal.dot(wi) * (1.0 / PI);
        match &self.lobe {
            None => cosine,
            Some(l) => (1.0 - l.chance) * cosine.max(0.0) + l.chance * lobe_pdf(l, wi),
        }
    }

    /// A direction to continue the path, f cos / pdf for it, and its pdf; None when it falls
    /// below the surface (`ng` the geometric normal on the path's side).
    pub(crate) fn sample(&self, u: Vec2, pick: impl FnOnce() -> f32, ng: Vec3) -> Option<(Vec3, Vec3, f32)> {
        let (t, b) = orthonormal_basis(self.normal);
        let Some(lobe) = &self.lobe else {
            let local = cosine_hemisphere(u);
            let wi = t * local.x + b * local.y + self.normal * local.z;
            return (local.z > 0.0 && ng.dot(wi) > 0.0).then(|| (wi, self.diffuse, local.z * (1.0 / PI)));
        };
        let wi = if pick() < lobe.chance {
            // cos(alpha) = u^(1 / (e + 1)) about the mirror direction: density (e + 1) / 2 pi cos^e.
            let cos = u.x.powf(1.0 / (lobe.exponent + 1.0));
            let sin = (1.0 - cos * cos).max(0.0).sqrt();
            let (mt, mb) = orthonormal_basis(lobe.mirror);
            let phi = 2.0 * PI * u.y;
            mt * (sin * phi.cos()) + mb * (sin * phi.sin()) + lobe.mirror * cos
        } else {
            let local = cosine_hemisphere(u);
            t * local.x + b * local.y + self.normal * local.z
        };
        let cos = self.normal.dot(wi);
        let pdf = self.pdf(wi);
        (cos > 0.0 && ng.dot(wi) > 0.0 && pdf > 0.0).then(|| (wi, self.eval(wi) * (cos / pdf), pdf))
    }
}

fn lobe_pdf(lobe: &Lobe, wi: Vec3) -> f32 {
    (lobe.exponent + 1.0) / (2.0 * PI) * wi.dot(lobe.mirror).max(0.0).powf(lobe.exponent)
}
