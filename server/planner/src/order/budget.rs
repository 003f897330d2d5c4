//! How much work a solver may do ([`SolveBudget`]) and the [`Meter`] that counts it.

/// How much work a solver may do.
#[derive(Clone, Copy)]
pub struct SolveBudget<'a> {
    /// Deterministic work bound: moves evaluated (a dynamic-programming pass counts one per node). Zero
    /// returns the construction.
    pub max_iterations: u64,
    /// Polled every 256 moves (and before the first): returning true stops the solver, which then returns
    /// the best tour found so far. For cancellation or a caller's deadline; the solver reads no clock.
    pub stop: Option<&'a dyn Fn() -> bool>,
}

impl<'a> SolveBudget<'a> {
    /// A budget of `max_iterations` moves without a stop hook.
    pub fn new(max_iterations: u64) -> Self {
        Self {
            max_iterations,
            stop: None,
        }
    }

    /// No bound beyond each strategy's own schedule (which always terminates).
    pub fn unlimited() -> Self {
        Self::new(u64::MAX)
    }

    /// The same budget, also stopped when `stop` returns true.
    pub fn with_stop(self, stop: &'a dyn Fn() -> bool) -> Self {
        Self {
            stop: Some(stop),
            ..self
        }
    }
}

impl std::fmt::Debug for SolveBudget<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SolveBudget")
            .field("max_iterations", &self.max_iterations)
            .field("stop", &self.stop.map(|_| "Fn"))
            .finish()
    }
}

/// Counts work against a [`SolveBudget`] and polls its stop hook every [`Meter::POLL`] units.
pub(crate) struct Meter<'a> {
    used: u64,
    max: u64,
    next_poll: u64,
    stop: Option<&'a dyn Fn() -> bool>,
    halted: bool,
}

impl<'a> Meter<'a> {
    const POLL: u64 = 256;

    pub fn new(budget: &SolveBudget<'a>) -> Self {
        Self {
            used: 0,
            max: budget.max_iterations,
            next_poll: 0,
            stop: budget.stop,
            halted: false,
        }
    }

    /// Charges `units` of work; false (from then on) once the budget is spent or the caller said stop.
    #[inline]
    pub fn spend(&mut self, units: u64) -> bool {
        if self.halted {
            return false;
        }
        if self.used >= self.max {
            self.halted = true;
            return false;
        }
        if self.used >= self.next_poll {
            self.next_poll = self.used.saturating_add(Self::POLL);
            if self.stop.is_some_and(|f| f()) {
                self.halted = true;
                return false;
            }
        }
        self.used = self.used.saturating_add(units);
        true
    }

    /// Charges one move evaluation.
    #[inline]
    pub fn tick(&mut self) -> bool {
        self.spend(1)
    }

    /// True once the budget is spent or the caller said stop.
    pub fn halted(&self) -> bool {
        self.halted
    }

    /// Work units left (0 when halted).
    pub fn remaining(&self) -> u64 {
        if self.halted {
            0
        } else {
            self.max.saturating_sub(self.used)
        }
    }
}
