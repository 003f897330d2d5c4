// The page's state: one site at a time, replaced as a whole when the operator picks another site.

export const TRAIL_MAX = 120; // poses kept per robot trail
export const ACTIVE_DOCS_MAX = 40; // active plans whose paths are drawn faintly

export const state = {
  view: null, // the MapView
  sites: [],
  site: null,
  summary: null,
  grid: null,
  plans: new Map(), // id -> PlanStatusResponse
  order: [], // plan ids, newest first
  selected: null,
  docs: new Map(), // id -> PlanDocument (selected and active plans)
  corrections: new Map(), // id -> [CorrectionDoc], oldest first
  streaming: new Map(), // id -> Map(region id -> RegionReady)
  robots: new Map(), // id -> { view: RobotView, draw: what the map draws }
  selectedRobot: null,
  missions: new Map(),
  allRobots: [],
  live: { count: 0, points: [], truncated: false },
  stream: null,
  planStream: null,
  pick: false,
  gen: 0, // bumped on every site change: answers for an older site are dropped
};
