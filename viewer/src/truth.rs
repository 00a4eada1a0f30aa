//! Truth on demand: the reference path tracer on the current view, on worker threads in the
//! background, progressively (passes of doubling samples, each with its own seed, averaged),
//! cancellable between passes, so the window stays responsive. The viewer polls its latest
//! image and compares the live frame with it.

use relume_bake::bvh::SceneBvh;
use relume_bake::image::Image;
use relume_bake::reference::{render_reference, ReferenceSettings};
use relume_bake::scene::Scene;
use relume_bake::work::WorkOptions;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

/// The latest average and how many samples per pixel it holds.
#[derive(Clone)]
pub struct Progress {
    pub image: Arc<Image>,
    pub samples: u32,
    pub target: u32,
}

pub struct Truth {
    target: u32,
    cancel: Arc<AtomicBool>,
    latest: Arc<Mutex<Option<Progress>>>,
}

impl Truth {
    /// Starts tracing `scene` (its camera and lights as the window shows them) at `width` x
    /// `height` to `samples` per pixel.
    pub fn start(scene: Scene, width: u32, height: u32, samples: u32) -> Truth {
        let cancel = Arc::new(AtomicBool::new(false));
        let latest = Arc::new(Mutex::new(None));
        let (stop, out) = (Arc::clone(&cancel), Arc::clone(&latest));
        // Detached: a pass under way ends on its own after a cancel, without holding the window.
        std::thread::spawn(move || trace(&scene, width, height, samples, &stop, &out));
        Truth { target: samples, cancel, latest }
    }

    pub fn latest(&self) -> Option<Progress> {
        self.latest.lock().ok().and_then(|l| l.clone())
    }

    /// Samples per pixel asked for.
    pub fn target(&self) -> u32 {
        self.target
    }

    pub fn finished(&self) -> bool {
        self.latest().is_some_and(|p| p.samples >= p.target)
    }
}

impl Drop for Truth {
    /// Cancels: the worker stops after its pass under way (at most 16 samples), unwaited.
    fn drop(&mut self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
}

fn trace(scene: &Scene, width: u32, height: u32, target: u32, cancel: &AtomicBool, out: &Mutex<Option<Progress>>) {
    let bvh = SceneBvh::new(scene);
    let mut sum = vec![glam::DVec3::ZERO; (width * height) as usize];
    let (mut samples, mut pass, mut seed) = (0u32, 1u32, 0u64);
    while samples < target && !cancel.load(Ordering::Relaxed) {
        let take = pass.min(target - samples);
        let work = WorkOptions { seed, ..WorkOptions::default() };
        let settings = ReferenceSettings { samples_per_pixel: take, width, height, work, ..ReferenceSettings::default() };
        let images = render_reference(scene, &bvh, &settings);
        for (s, p) in sum.iter_mut().zip(&images.combined.pixels) {
            *s += p.as_dvec3() * take as f64;
        }
        samples += take;
        let mut image = Image::new(width, height);
        for (p, s) in image.pixels.iter_mut().zip(&sum) {
            *p = (*s / samples as f64).as_vec3();
        }
        if let Ok(mut latest) = out.lock() {
            *latest = Some(Progress { image: Arc::new(image), samples, target });
        }
        (pass, seed) = ((pass * 2).min(16), seed + 1);
    }
}
