//! Bidirectional A* (seed 003 §2.2): one A* grows from `a`, another from `b` over the reversed (here:
//! identical, the cost is symmetric) moves; they alternate one expansion each.
//!
//! The seed stops "when the explored node of one path is in the other's explored set". That first meeting is
//! not optimal in general, so we keep the best meeting cost μ seen so far (updated whenever an expanded cell
//! already has a cost from the other side) and stop only when μ ≤ max(min f of the forward open list,
//! min f of the backward open list). With consistent heuristics each side's smallest f is at most the
//! optimal cost C* while that side has not expanded the whole optimal path — and once it has, μ = C* was
//! recorded when the path's last cell was expanded — so at the stop μ = C*: the same cost as forward A*.
//!
//! The price of that guarantee: both searches must each reach μ in their own f, so on open maps this
//! expands more cells than forward A* (about 1.8× on the 4 M-cell benchmark). It is offered for parity
//! with seed 003 and for cases where the goal side is enclosed (its search ends early).

use super::astar::{Attachment, Entry, Found, Frontier, STEP_CELLS, Search};

/// Bidirectional A* between `roots` (around `a`) and `goals` (around `b`).
pub(crate) fn search(
    s: &Search<'_, '_>,
    fwd: &mut Frontier,
    bwd: &mut Frontier,
    roots: &[Attachment],
    goals: &[Attachment],
) -> Option<Found> {
    let to_goals = s.goal_frame(goals);
    let to_roots = s.goal_frame(roots);
    s.seed(fwd, roots, &to_goals);
    s.seed(bwd, goals, &to_roots);
    let res = s.graph.resolution;

    let mut mu = f64::INFINITY;
    let mut meet = None;
    for &(i, _) in goals {
        let through = fwd.g(i) + bwd.g(i);
        if through < mu {
            mu = through;
            meet = Some(i);
        }
    }

    let mut forward = true;
    loop {
        let top = fwd.top_key().max(bwd.top_key());
        // Also stops when either side ran empty (top = ∞): its component holds no further meeting.
        if mu <= top {
            break;
        }
        if top > s.max_cost {
            return None;
        }
        let (this, other, target) = if forward {
            (&mut *fwd, &*bwd, &to_goals)
        } else {
            (&mut *bwd, &*fwd, &to_roots)
        };
        forward = !forward;
        let Some(e) = this.pop_open() else { break };
        let u = e.cell as usize;
        let gu = this.g(u);
        this.close(u);
        let through = gu + other.g(u);
        if through < mu {
            mu = through;
            meet = Some(u);
        }
        let psi_u = s.psi_cell(u);
        s.graph.for_each_move(u, |v, d, vx, vy| {
            if this.is_closed(v) {
                return;
            }
            let gv = gu + s.edge(STEP_CELLS[d] * res, psi_u, s.psi_cell(v));
            if gv < this.g(v) {
                this.set(v, gv, d as u8);
                this.heap.push(Entry {
                    key: gv + s.heuristic((vx, vy), target),
                    cell: v as u32,
                });
            }
        });
    }

    let m = meet?;
    let mut cells = s.trace(fwd, m);
    let back = s.trace(bwd, m);
    cells.extend(back.iter().rev().skip(1));
    Some(Found {
        cells,
        cost: mu,
        expanded: fwd.expanded + bwd.expanded,
    })
}
