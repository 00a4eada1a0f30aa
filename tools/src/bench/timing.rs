//! Frame times a user can trust: the renderers of every configuration of a scene are warmed
//! up, then timed one frame each in turn, round after round, so that whatever else the
//! machine does at a moment falls on every method alike instead of on whichever ran then.

use super::results::{self, FrameCost};
use crate::gpu::{median_timings, warm_up};
use anyhow::Result;
use relume_renderer::{FrameTimings, Headless};
use std::time::Instant;

/// Each renderer warmed up (crate::gpu::warm_up), then `frames` rounds that time one frame of
/// each in turn: GPU time per pass from timestamps, and the CPU's wall time of each `render`
/// call (record, submit, wait for its fence). A renderer that fails is left out of the
/// rounds after it failed; the others go on.
pub(super) fn time_interleaved(renderers: &mut [&mut Headless], frames: u32, warm_up_seconds: f64) -> Vec<Result<FrameCost>> {
    let mut timed: Vec<Result<Timed>> =
        renderers.iter_mut().map(|renderer| warm_up(renderer, warm_up_seconds).map(|()| Timed::default())).collect();
    round_robin(renderers, &mut timed, frames, |renderer, timed| timed.frame(renderer));
    timed.into_iter().map(|t| t.map(Timed::cost)).collect()
}

/// `rounds` rounds, each calling `step` once on every item whose state is still Ok, in
/// order; a step's error becomes that item's state and ends its rounds.
fn round_robin<T, S>(items: &mut [T], states: &mut [Result<S>], rounds: u32, mut step: impl FnMut(&mut T, &mut S) -> Result<()>) {
    for _ in 0..rounds {
        for (item, state) in items.iter_mut().zip(states.iter_mut()) {
            let Ok(s) = state else { continue };
            if let Err(why) = step(item, s) {
                *state = Err(why);
            }
        }
    }
}

/// One renderer's timed frames so far.
#[derive(Default)]
struct Timed {
    gpu: Vec<FrameTimings>,
    cpu_ms: Vec<f64>,
}

impl Timed {
    fn frame(&mut self, renderer: &mut Headless) -> Result<()> {
        let start = Instant::now();
        self.gpu.push(renderer.render()?);
        self.cpu_ms.push(start.elapsed().as_secs_f64() * 1e3);
        Ok(())
    }

    fn cost(self) -> FrameCost {
        let totals: Vec<f64> = self.gpu.iter().filter(|t| !t.passes().is_empty()).map(|t| t.total_ms()).collect();
        FrameCost {
            passes_ms: median_timings(&self.gpu).into_iter().filter(|(name, _)| name != "frame").collect(),
            gpu_ms: results::percentile(&totals, 0.5),
            gpu_p10_ms: results::percentile(&totals, 0.1),
            gpu_p90_ms: results::percentile(&totals, 0.9),
            cpu_ms: results::percentile(&self.cpu_ms, 0.5),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounds_take_one_step_of_each_in_turn_and_a_failure_ends_only_its_own() {
        let mut log = Vec::new();
        let mut items = ['a', 'b', 'c'];
        let mut states: Vec<Result<u32>> = vec![Ok(0), Ok(0), Ok(0)];
        round_robin(&mut items, &mut states, 3, |item, count| {
            log.push(*item);
            *count += 1;
            match (*item, *count) {
                ('b', 2) => anyhow::bail!("b's second frame failed"),
                _ => Ok(()),
            }
        });
        assert_eq!(log.iter().collect::<String>(), "abcabcac");
        assert_eq!(states[0].as_ref().unwrap(), &3);
        assert!(states[1].as_ref().unwrap_err().to_string().contains("second frame"));
        assert_eq!(states[2].as_ref().unwrap(), &3);
    }
}
