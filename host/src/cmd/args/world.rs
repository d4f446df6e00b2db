//! The world a mission runs in: `--params`, `--known` and `--size`, the options `twil simulate`
//! and `twil mission` share (each adds its own `--real`: required by the simulator, refused
//! by a board); and the planning problem of `twil plan` and `twil compare`: `--params`,
//! `--size`, `--resolution`, `--robot` (each adds its own `--world`).
//!
//! `--size` has one grammar in every command, [`parse_size`] (`15x10`, `15X10`, or `15` for a
//! square), given to clap as the value parser: a bad value is a usage error that names the
//! option and the value.

use std::path::PathBuf;

use anyhow::{anyhow, bail, Result};
use twil_core::grid::GridGeometry;
use twil_core::world::{Obstacles, Params};

pub use crate::planning::{parse_size, SizeM};

use super::{read_da, read_par};
use crate::answer::OffMap;
use crate::planning::WorldFiles;

/// `--params`, `--known`, `--size`.
#[derive(clap::Args, Debug, Clone)]
pub struct WorldArgs {
    /// The mission (.par): radius, speed, initial heading, start, goal.
    #[arg(long, value_name = "P.par")]
    pub params: PathBuf,
    /// Obstacles known before the first sweep (.da).
    #[arg(long, value_name = "K.da")]
    pub known: Option<PathBuf>,
    /// Map size in metres, WIDTHxHEIGHT (or one number for a square).
    #[arg(long, default_value = "15x15", value_name = "WxH", value_parser = parse_size)]
    pub size: SizeM,
}

impl WorldArgs {
    /// The `.par` mission and the `--known` obstacles, read and checked (errors name the file
    /// and the line).
    pub fn read(&self) -> Result<(Params, Option<Obstacles>)> {
        let params = read_par(&self.params)?;
        let known = self.known.as_deref().map(read_da).transpose()?;
        Ok((params, known))
    }

    /// The map of `--size` in cells of `resolution_m`: at most 400 x 400 cells, the host's
    /// grid (and a simulated device's).
    pub fn geometry(&self, resolution_m: f32) -> Result<GridGeometry> {
        let size = self.size;
        let what = || format!("--size {size} at {resolution_m} m cells");
        let geometry = GridGeometry::from_size_m(size.width_m, size.height_m, resolution_m)
            .map_err(|e| anyhow!("{}: {e}", what()))?;
        if geometry.cell_count() > 400 * 400 {
            bail!(
                "{}: {} x {} cells; at most 400 x 400",
                what(),
                geometry.width(),
                geometry.height()
            );
        }
        Ok(geometry)
    }

    /// `Err` when the start or the goal of `params` lies off `geometry`, the map of
    /// `--size`: the commands answer `out_of_bounds` ([`crate::answer::OffMap`]).
    pub fn check_on_map(&self, geometry: &GridGeometry, params: &Params) -> Result<(), OffMap> {
        OffMap::check(&self.params, &self.size.to_string(), geometry, params)
    }
}

/// `--params`, `--size`, `--resolution`, `--robot` of `twil plan` and `twil compare`.
#[derive(clap::Args, Debug, Clone)]
pub struct PlanningArgs {
    /// Mission parameters (.par): robot radius, speed, heading, start, goal.
    #[arg(long, value_name = "P.par")]
    pub params: PathBuf,
    /// Map size in metres, WIDTHxHEIGHT (or one number for a square).
    #[arg(long, default_value = "15x15", value_name = "WxH", value_parser = parse_size)]
    pub size: SizeM,
    /// Cell side in metres (the grid planners'; in `twil compare` also Voronoi's, the
    /// quadtree's and the potential field's).
    #[arg(long, default_value_t = 0.05)]
    pub resolution: f32,
    /// Robot file (`twil robot init`): its `planning_radius_m`, if set, replaces the `.par`
    /// radius; every value is checked against the robot model. `twil compare`: its
    /// `sonar_range_m` is the Bug robot's unless --sonar-range is given.
    #[arg(long, value_name = "FILE.toml")]
    pub robot: Option<PathBuf>,
}

impl PlanningArgs {
    /// The files to read ([`crate::planning::load_world`]): these options with the command's
    /// `.da` polygons (`world`) and saved map (`map`), if any.
    pub fn files(&self, world: Option<PathBuf>, map: Option<PathBuf>) -> WorldFiles {
        WorldFiles {
            world,
            params: self.params.clone(),
            map,
            size: self.size,
            resolution_m: self.resolution,
            robot: self.robot.clone(),
        }
    }
}
