//! LunarLander (being written).

use super::{Env, EnvSpec, Geometry, RenderState, Step};

pub struct LunarLander {}

impl LunarLander {
    pub fn new() -> Self {
        todo!()
    }
}

impl Default for LunarLander {
    fn default() -> Self {
        Self::new()
    }
}

impl Env for LunarLander {
    fn spec(&self) -> &EnvSpec {
        todo!()
    }
    fn reset(&mut self, _seed: u64) -> Vec<f32> {
        todo!()
    }
    fn step(&mut self, _action: &[f32]) -> Step {
        todo!()
    }
    fn observation(&self) -> Vec<f32> {
        todo!()
    }
    fn elapsed_steps(&self) -> u32 {
        todo!()
    }
    fn render(&self) -> RenderState {
        todo!()
    }
    fn geometry(&self) -> Geometry {
        todo!()
    }
}

pub fn heuristic(_obs: &[f32]) -> [f32; 2] {
    todo!()
}
