//! The repair entry point: optimiser, then detour, then skip (see the [module docs](super)).

use crate::geom::Point2;

use super::Repair;
use super::error::CorrectError;
use super::judge::Breach;
use super::params::CorrectParams;
use super::world::World;

/// Replaces the stretch of `path` around `breach` by a collision-free patch (see [`super`]). Fails on invalid
/// params, an unusable path or breach, or a start anchor in collision; never returns a colliding patch.
pub fn repair(path: &[Point2], breach: &Breach, world: &World<'_>, p: &CorrectParams) -> Result<Repair, CorrectError> {
    p.validate()?;
    world.check()?;
    let _ = (path, breach);
    Err(CorrectError::BadPath("repair is being implemented".into()))
}
