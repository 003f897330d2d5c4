//! The simulation, sans-IO: the world and its robots advanced in fixed steps of simulated time, producing the
//! odometry and scans to publish. The caller carries messages in and out and keeps the clock.

use crate::drive::DiffDrive;
use crate::lidar::Lidar;
use crate::robot::SimRobot;
use crate::world::World;

/// Rates and sizes of the simulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimConfig {
    /// Step of simulated time, seconds (also the trace's sampling).
    pub dt: f64,
    /// Odometry rate, Hz of simulated time.
    pub odom_hz: f64,
    /// Scan rate, Hz of simulated time.
    pub scan_hz: f64,
    /// The laser.
    pub lidar: Lidar,
    /// Dynamic-tracking threshold, metres (0: stop at every waypoint).
    pub mu: f64,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            dt: 0.05,
            odom_hz: 20.0,
            scan_hz: 10.0,
            lidar: Lidar::default(),
            mu: 0.2,
        }
    }
}

/// A message a step produces for robot `robot` (an index into [`Simulation::robots`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Outgoing {
    /// The robot's pose and velocities.
    Odom {
        /// Robot index.
        robot: usize,
        /// Its body now.
        body: DiffDrive,
    },
    /// A scan taken now.
    Scan {
        /// Robot index.
        robot: usize,
        /// Ranges, one per beam from the heading counter-clockwise.
        ranges: Vec<f32>,
    },
}

/// The world and its robots.
#[derive(Debug, Clone)]
pub struct Simulation {
    /// The world.
    pub world: World,
    /// The robots.
    pub robots: Vec<SimRobot>,
    /// Its settings.
    pub config: SimConfig,
    /// Simulated time, seconds since the start.
    pub t: f64,
    steps: u64,
}

fn every(dt: f64, hz: f64) -> u64 {
    if hz > 0.0 {
        ((1.0 / (hz * dt)).round() as u64).max(1)
    } else {
        u64::MAX
    }
}

impl Simulation {
    /// A simulation at time 0.
    pub fn new(world: World, robots: Vec<SimRobot>, config: SimConfig) -> Self {
        Self {
            world,
            robots,
            config,
            t: 0.0,
            steps: 0,
        }
    }

    /// True when every robot has finished its plan.
    pub fn all_finished(&self) -> bool {
        self.robots.iter().all(SimRobot::finished)
    }

    /// Advances one step: movers walk, robots drive; returns the odometry and scans due at the new time.
    pub fn step(&mut self) -> Vec<Outgoing> {
        let dt = self.config.dt;
        self.steps += 1;
        self.t = self.steps as f64 * dt;
        let bodies: Vec<_> = self.robots.iter().map(|r| (r.position(), r.spec.radius)).collect();
        self.world.step_movers(dt, &bodies);
        let mut out = Vec::new();
        let odom_due = self.steps.is_multiple_of(every(dt, self.config.odom_hz));
        let scan_due = self.steps.is_multiple_of(every(dt, self.config.scan_hz));
        for (i, robot) in self.robots.iter_mut().enumerate() {
            robot.step(&self.world, self.t, dt);
            if odom_due {
                out.push(Outgoing::Odom {
                    robot: i,
                    body: robot.body,
                });
            }
            if scan_due {
                let ranges = self.config.lidar.scan(&self.world, &robot.body);
                robot.observe(&self.config.lidar.points(&ranges), &self.world.grid);
                out.push(Outgoing::Scan { robot: i, ranges });
            }
        }
        out
    }
}
