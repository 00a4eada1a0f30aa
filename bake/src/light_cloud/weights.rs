//! A user's point light as a weighted sum of cloud lights (004 §6.1): the m nearest cloud
//! lights visible from it, weighted by Silverman's kernel (1 - d / r)^4, normalised, times the
//! light's intensity. Several lights add their weights. With zones (§4.2), each zone has its
//! own cloud lights and a light stands on the nearest of each zone's.
//!
//! r is the distance of the (m + 1)-th nearest visible cloud light (spec light-clouds.md B4):
//! with the paper's r = d_(m) the m-th weight is always zero, and a light leaving the set
//! would jump. With this r a light leaves the set at weight zero, so the weights are
//! continuous as the light moves, except where visibility changes.
//!
//! A user's directional light stands likewise on the cloud's directions (`LightCloud::directions`)
//! nearest it by angle, the same kernel over angles, none hidden, times its illuminance (lux).
//!
//! A cloud of emission bands (`LightCloud::emission`) takes spot lights too: each cloud light's
//! weight is shared out over its emission functions by the light's own coefficients in them
//! (`emission`), so that the cone's light leaves the cloud lights where the spot points.

use crate::scene::{Light, LightKind};
use crate::sh;
use glam::Vec3;

/// One column's weight (per channel, candela; lux for a direction's): a cloud light's, or one emission function's of
/// it (column = light x emission functions + function).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CloudWeight {
    pub column: u32,
    pub weight: Vec3,
}

/// The most cloud lights one user light stands on.
pub const MAX_NEAREST: usize = 16;

/// Refuses a directional light when the cloud has no directions to stand it on (004 §4.1: its
/// light comes from no point of the cloud).
pub fn refuse_lights(lights: &[Light], directions: usize) -> Result<(), String> {
    match lights.iter().find(|l| l.kind == LightKind::Directional).filter(|_| directions == 0) {
        Some(l) => Err(format!(
            "light \"{}\" is a directional light and the bake has no cloud of directions to stand it on (a directional light comes from no point of the cloud; 004 §4.1): bake with it in the scene, or with --directions N",
            l.name
        )),
        None => Ok(()),
    }
}

/// A light's intensity pattern as coefficients of the cloud's emission functions e_k(w) =
/// y_k(w) / y_0 (`crate::sh`, the first `count`): I(w) ~ sum_k c_k e_k(w) times its rgb
/// intensity. c_0 is the light's mean over the sphere (1 for a point light, whose other
/// coefficients are 0). A spot's cone factor s depends on w . d alone, so by the Funk-Hecke
/// theorem c_k = sqrt(pi) y_k(d) integral_-1^1 s(t) P_l(t) dt for k of band l: the cone's
/// Legendre expansion turned to the spot's axis. The integral is exact: s is 0, a square of a
/// linear function, then 1, and 3-point Gauss-Legendre integrates each piece times P_l
/// (degree <= 5) exactly.
pub fn emission(light: &Light, count: usize) -> [f32; sh::COEFFICIENTS] {
    let mut c = [0.0; sh::COEFFICIENTS];
    let LightKind::Spot { inner_cone, outer_cone } = light.kind else {
        c[0] = 1.0;
        return c;
    };
    let (cos_outer, cos_inner) = (outer_cone.cos() as f64, inner_cone.cos() as f64);
    let scale = 1.0 / (cos_inner - cos_outer).max(1e-3);
    let cone = |t: f64| ((t - cos_outer) * scale).clamp(0.0, 1.0).powi(2);
    let legendre = |l: usize, t: f64| match l {
        0 => 1.0,
        1 => t,
        2 => (3.0 * t * t - 1.0) / 2.0,
        _ => (5.0 * t * t * t - 3.0 * t) / 2.0,
    };
    let gauss = |a: f64, b: f64, f: &dyn Fn(f64) -> f64| {
        let (m, h) = ((a + b) / 2.0, (b - a) / 2.0);
        let x = (0.6f64).sqrt() * h;
        h * (5.0 * f(m - x) + 8.0 * f(m) + 5.0 * f(m + x)) / 9.0
    };
    // The ramp ends where it reaches 1 (cos_inner, or later when the 1e-3 floor flattens it).
    let top = (cos_outer + 1.0 / scale).min(1.0);
    let y = sh::eval(light.direction);
    for (k, c) in c.iter_mut().enumerate().take(count) {
        let l = (k as f32).sqrt() as usize;
        let band = gauss(cos_outer, top, &|t| cone(t) * legendre(l, t)) + gauss(top, 1.0, &|t| legendre(l, t));
        *c = (std::f64::consts::PI.sqrt() * band) as f32 * y[k];
    }
    c
}

/// Computes weights without allocating once made: its scratch is sized for the cloud (and,
/// at the first weighing, for the number of user lights).
pub struct Weigher {
    nearest: usize,
    /// Zone z's cloud lights are `zone_lights[z]..zone_lights[z + 1]`.
    zone_lights: Vec<u32>,
    /// Emission functions (columns) a cloud light has.
    emission: usize,
    /// How many of each zone's cloud lights, its last, are directions, and how many of them a
    /// directional light stands on.
    directions: usize,
    nearest_directions: usize,
    /// Seconds a cloud light takes to fade in or out as visibility changes; 0 (the default):
    /// at once.
    fade_seconds: f32,
    /// `[user light][cloud light]`: how far each cloud light is faded in for each user light.
    faded: Vec<f32>,
    order: Vec<(f32, u32)>,
    chosen: Vec<(f32, u32)>,
    /// Per column.
    dense: Vec<Vec3>,
}

impl Weigher {
    /// For a cloud of `cloud_size` lights in one zone, each user light standing on its
    /// `nearest` (m) nearest visible ones.
    pub fn new(cloud_size: usize, nearest: usize) -> Result<Weigher, String> {
        Weigher::zoned(vec![0, cloud_size as u32], nearest)
    }

    /// For a cloud in zones (`LightCloud::zone_lights`), each user light standing on the
    /// `nearest` (m) nearest visible lights of every zone.
    pub fn zoned(zone_lights: Vec<u32>, nearest: usize) -> Result<Weigher, String> {
        let cloud_size = zone_lights.last().map_or(0, |&n| n as usize);
        if !(1..=MAX_NEAREST).contains(&nearest) {
            return Err(format!("m = {nearest}: a light stands on 1..={MAX_NEAREST} nearest cloud lights"));
        }
        Ok(Weigher {
            nearest,
            zone_lights,
            emission: 1,
            directions: 0,
            nearest_directions: 1,
            fade_seconds: 0.0,
            faded: Vec::new(),
            order: Vec::with_capacity(cloud_size),
            chosen: Vec::with_capacity(MAX_NEAREST + 1),
            dense: vec![Vec3::ZERO; cloud_size],
        })
    }

    /// The same, for cloud lights of `count` emission functions each (`LightCloud::emission`).
    pub fn with_emission(self, count: usize) -> Result<Weigher, String> {
        if !super::EMISSION_COUNTS.contains(&count) {
            return Err(format!("{count} emission functions a cloud light: one of {:?}", super::EMISSION_COUNTS));
        }
        let columns = self.dense.len() * count / self.emission;
        Ok(Weigher { emission: count, dense: vec![Vec3::ZERO; columns], ..self })
    }

    /// The same, for a cloud whose zones end with `count` directions
    /// (`LightCloud::directions`), each directional light standing on its `nearest`.
    pub fn with_directions(self, count: usize, nearest: usize) -> Result<Weigher, String> {
        if !(1..=MAX_NEAREST).contains(&nearest) {
            return Err(format!("{nearest} nearest directions: a directional light stands on 1..={MAX_NEAREST}"));
        }
        if let Some(z) = self.zone_lights.windows(2).position(|w| ((w[1] - w[0]) as usize) < count) {
            return Err(format!("{count} directions: zone {z} has fewer lights"));
        }
        Ok(Weigher { directions: count, nearest_directions: nearest, ..self })
    }

    /// The same, with cloud lights fading in and out over `seconds` as visibility changes
    /// (0: at once).
    pub fn with_fade(self, seconds: f32) -> Result<Weigher, String> {
        if !(seconds.is_finite() && seconds >= 0.0) {
            return Err(format!("a fade of {seconds} s: must be a finite number of seconds >= 0"));
        }
        Ok(Weigher { fade_seconds: seconds, ..self })
    }

    /// The weights of `lights` over `cloud`, settled (a cut: every fade done), in column
    /// order, zero weights left out, written to `out`; `visible(from, to)` says whether a segment is
    /// unoccluded. Returns how many lights saw no cloud light of some zone (they add no
    /// indirect light there: spec B14).
    pub fn weigh(
        &mut self,
        cloud: &[Vec3],
        lights: &[Light],
        visible: impl FnMut(Vec3, Vec3) -> bool,
        out: &mut Vec<CloudWeight>,
    ) -> usize {
        self.weigh_after(cloud, lights, visible, None, out)
    }

    /// As [`Weigher::weigh`], `elapsed` seconds after the last weighing (None: a cut): cloud
    /// lights that came into or went out of sight fade in or out over the weigher's fade
    /// (spec light-clouds.md B5: w_j = f_j (1 - d_j / r)^4 before normalising, f_j stepping
    /// by elapsed / fade towards 1 while j is among the nearest visible, towards 0 after).
    pub fn weigh_after(
        &mut self,
        cloud: &[Vec3],
        lights: &[Light],
        mut visible: impl FnMut(Vec3, Vec3) -> bool,
        elapsed: Option<f32>,
        out: &mut Vec<CloudWeight>,
    ) -> usize {
        // A new number of lights starts settled.
        let step = match elapsed {
            Some(dt) if self.fade_seconds > 0.0 && self.faded.len() == lights.len() * cloud.len() => dt.max(0.0) / self.fade_seconds,
            _ => f32::INFINITY,
        };
        self.faded.resize(lights.len() * cloud.len(), 0.0);
        self.dense.iter_mut().for_each(|w| *w = Vec3::ZERO);
        let mut unseen = 0;
        for (k, light) in lights.iter().enumerate() {
            let mut seen = true;
            for zone in 0..self.zone_lights.len() - 1 {
                let (start, end) = (self.zone_lights[zone] as usize, self.zone_lights[zone + 1] as usize);
                let (points, directions) = (start..end - self.directions, end - self.directions..end);
                let faded_at = k * cloud.len();
                seen &= match light.kind {
                    // Directions are never hidden, so never fade.
                    LightKind::Directional => {
                        let angle = |j: usize| cloud[j].dot(light.direction).clamp(-1.0, 1.0).acos();
                        self.add(directions, faded_at, light, (f32::INFINITY, self.nearest_directions), angle, |_| true)
                    }
                    _ => {
                        let distance = |j: usize| cloud[j].distance(light.position);
                        self.add(points, faded_at, light, (step, self.nearest), distance, |j| visible(light.position, cloud[j]))
                    }
                };
            }
            unseen += usize::from(!seen);
        }
        out.clear();
        out.extend(
            self.dense.iter().enumerate().filter(|(_, w)| **w != Vec3::ZERO).map(|(j, w)| CloudWeight { column: j as u32, weight: *w }),
        );
        unseen
    }

    /// Adds one light's weights over the cloud lights `zone` (a zone's points, or its
    /// directions), the `nearest` visible ones by `distance` (`faded_at`: where the light's fade
    /// factors start, which move by `step`); false when none is visible from it.
    fn add(
        &mut self,
        zone: std::ops::Range<usize>,
        faded_at: usize,
        light: &Light,
        (step, nearest): (f32, usize),
        distance: impl Fn(usize) -> f32,
        mut visible: impl FnMut(usize) -> bool,
    ) -> bool {
        self.order.clear();
        self.order.extend(zone.clone().map(|j| (distance(j), j as u32)));
        self.order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        self.chosen.clear();
        for &(d, j) in &self.order {
            if self.chosen.len() > nearest {
                break;
            }
            if visible(j as usize) {
                self.chosen.push((d, j));
            }
        }
        let Some(&(r, _)) = self.chosen.last() else { return false };
        let used = &self.chosen[..self.chosen.len().min(nearest)];
        let faded = &mut self.faded[faded_at + zone.start..faded_at + zone.end];
        for (f, j) in faded.iter_mut().zip(zone.clone()) {
            let wanted = used.iter().any(|&(_, u)| u as usize == j);
            *f = if wanted { (*f + step).min(1.0) } else { (*f - step).max(0.0) };
        }
        // 004 §6.1: Silverman's kernel, normalised to sum to one.
        let kernel = |d: f32| if r > 0.0 { (1.0 - d / r).max(0.0).powi(4) } else { 1.0 };
        let weight = |j: usize| faded[j - zone.start] * kernel(distance(j));
        let total: f32 = zone.clone().map(weight).sum();
        let coefficients = emission(light, self.emission);
        let mut add = |j: usize, share: f32| {
            let columns = &mut self.dense[j * self.emission..][..self.emission];
            columns.iter_mut().zip(coefficients).for_each(|(w, c)| *w += light.intensity * (share * c));
        };
        if total > 0.0 {
            zone.clone().for_each(|j| add(j, weight(j) / total));
        } else {
            // Every used light at distance r (ties): equal weights (spec B4).
            used.iter().for_each(|&(_, j)| add(j as usize, 1.0 / used.len() as f32));
        }
        true
    }
}
