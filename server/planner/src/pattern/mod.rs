//! In-region coverage patterns: what a region's sweep is made of.
//!
//! A pattern turns one region into [`Task`]s — polylines the robot must drive, in either direction: the
//! boustrophedon lanes ([`lanes`]), the rings of a spiral ([`spiral`]) spliced into one loop
//! ([`ring_splice`]), and the targeted passes that cover
//! what those miss ([`boundary`]: stretches of the wall contour, excursions from the pattern into pockets
//! next to it ([`excursion`]), and single visits into the other pockets), and the
//! frame along a region's walls that inset lanes leave to it ([`frame`]). Ordering
//! the tasks and linking them is the job of `order` and `link`.

pub mod boundary;
pub mod contour;
pub mod excursion;
pub mod frame;
pub mod lanes;
pub mod ring_splice;
pub mod spiral;

use crate::geom::Point2;

/// What a task is for (kept for rendering and statistics).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TaskKind {
    /// A straight boustrophedon lane.
    Lane,
    /// A ring of a spiral (a closed loop).
    Ring,
    /// A stretch of wall or obstacle contour that lanes cannot reach.
    Boundary,
    /// A single point to visit, covering a pocket.
    Visit,
    /// A stretch of a region's contour along walls, driven as part of the main pattern (framed lanes).
    Frame,
}

/// A polyline to drive (map frame, metres). Open tasks may be driven in either direction; closed tasks
/// (rings) start and end at the same vertex and may start at any vertex.
#[derive(Debug, Clone, PartialEq)]
pub struct Task {
    /// The vertices; straight segments between them. Every segment keeps the robot's clearance.
    pub points: Vec<Point2>,
    /// What the task is for.
    pub kind: TaskKind,
}

impl Task {
    /// Length of the polyline, metres.
    pub fn length(&self) -> f64 {
        crate::geom::polyline_length(&self.points)
    }

    /// True for closed loops (first vertex equals the last).
    pub fn is_closed(&self) -> bool {
        self.points.len() > 2 && self.points.first() == self.points.last()
    }
}

/// The in-region patterns the planner offers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub enum PatternMethod {
    /// Boustrophedon lanes along each region's best direction.
    #[default]
    Lanes,
    /// Rings from the region's edge inwards, one tool width apart.
    Spiral,
}

impl PatternMethod {
    /// Every pattern, in CLI order.
    pub const ALL: [Self; 2] = [Self::Lanes, Self::Spiral];

    /// The CLI / API name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Lanes => "lanes",
            Self::Spiral => "spiral",
        }
    }
}

impl std::str::FromStr for PatternMethod {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("unknown pattern {s:?}; expected lanes or spiral"))
    }
}

/// Test support: the whole reachable set of a space as region 0.
#[cfg(test)]
pub(crate) struct WholeRegion {
    labels: Vec<u32>,
    target_labels: Vec<u32>,
    cells: Vec<usize>,
    targets: Vec<usize>,
}

#[cfg(test)]
impl WholeRegion {
    pub(crate) fn new(space: &crate::space::CoverageSpace) -> Self {
        let n = space.geometry().len();
        let label = |on: &[bool]| (0..n).map(|i| if on[i] { 0 } else { u32::MAX }).collect();
        Self {
            labels: label(&space.reachable),
            target_labels: label(&space.coverable),
            cells: (0..n).filter(|&i| space.reachable[i]).collect(),
            targets: (0..n).filter(|&i| space.coverable[i]).collect(),
        }
    }

    pub(crate) fn view(&self) -> lanes::RegionView<'_> {
        lanes::RegionView {
            id: 0,
            labels: &self.labels,
            target_labels: &self.target_labels,
            cells: &self.cells,
            targets: &self.targets,
        }
    }
}
