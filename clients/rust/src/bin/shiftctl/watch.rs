//! `plan … --watch` and `mission create … --watch`: follow the server-sent events — a progress bar for people
//! (a plan's regions counted as they stream; a mission's status and planned coverage), one JSON document per
//! line for scripts — then print the final status: a plan's metrics, a mission's table.

use indicatif::{ProgressBar, ProgressStyle};
use shift_client::Client;
use shift_client::proto::{MissionStatus, MissionView, PlanEvent, PlanStatus, PlanStatusResponse};

use crate::show;

/// Steps of the bar (progress is 0-1).
const STEPS: u64 = 1000;

/// Follows `plan_id` until its computation ended; an error when it failed or was cancelled.
pub async fn follow(client: &Client, plan_id: &str, json: bool) -> anyhow::Result<()> {
    let mut events = client.events(plan_id).await?;
    let bar = bar(plan_id, json);
    let mut regions = 0u32;
    let mut last: Option<PlanStatusResponse> = None;
    while let Some(event) = events.next_event().await? {
        if json {
            println!("{}", serde_json::to_string(&event)?);
        }
        match event {
            PlanEvent::Progress { progress, .. } => bar.set_position(position(progress)),
            PlanEvent::RegionReady { .. } => {
                regions += 1;
                bar.set_message(format!("planning, {regions} regions ready"));
            }
            PlanEvent::Status(s) => {
                bar.set_position(position(s.progress));
                regions = regions.max(s.regions_ready);
                bar.set_message(format!("{}, {regions} regions ready", s.status.as_str()));
                let done = s.status.is_final();
                last = Some(s);
                if done {
                    break;
                }
            }
            PlanEvent::Correction(_) => {}
        }
    }
    bar.finish_and_clear();
    let status = match last {
        Some(s) if s.status.is_final() => s,
        // The stream ended early (daemon shutting down): ask once more.
        _ => client.plan(plan_id).await?,
    };
    if !json {
        println!(
            "plan {} {} ({} regions streamed)",
            status.plan_id,
            status.status.as_str(),
            regions
        );
        if let Some(m) = &status.metrics {
            print!("{}", show::metrics(m));
        }
    }
    match status.status {
        PlanStatus::Failed | PlanStatus::Cancelled => anyhow::bail!(
            "plan {} {}: {}",
            status.plan_id,
            status.status.as_str(),
            status.error.as_deref().unwrap_or("no reason given")
        ),
        s if s.is_final() => Ok(()),
        s => anyhow::bail!(
            "plan {} is still {} (the event stream ended)",
            status.plan_id,
            s.as_str()
        ),
    }
}

/// Follows mission `mission_id` until it is planned (ready, or later), then prints its table; an error when
/// it failed or was cancelled.
pub async fn follow_mission(client: &Client, mission_id: &str, json: bool) -> anyhow::Result<()> {
    let mut views = client.mission_events(mission_id).await?;
    let bar = bar(mission_id, json);
    let mut last: Option<MissionView> = None;
    while let Some(view) = views.next_view().await? {
        if json {
            println!("{}", serde_json::to_string(&view)?);
        }
        bar.set_position(position(view.progress));
        let planned = view.plans.iter().filter(|p| p.version > 0).count();
        bar.set_message(format!(
            "{}, {planned} of {} plans computed",
            view.status.as_str(),
            view.plans.len()
        ));
        let planning = matches!(view.status, MissionStatus::Queued | MissionStatus::Planning);
        last = Some(view);
        if !planning {
            break;
        }
    }
    bar.finish_and_clear();
    let view = match last {
        Some(v) if !matches!(v.status, MissionStatus::Queued | MissionStatus::Planning) => v,
        // The stream ended early (daemon shutting down): ask once more.
        _ => client.mission(mission_id).await?,
    };
    if !json {
        print!("{}", show::mission(&view));
    }
    match view.status {
        MissionStatus::Failed | MissionStatus::Cancelled => anyhow::bail!(
            "mission {} {}: {}",
            view.mission_id,
            view.status.as_str(),
            view.error.as_deref().unwrap_or("no reason given")
        ),
        MissionStatus::Queued | MissionStatus::Planning => anyhow::bail!(
            "mission {} is still {} (the event stream ended)",
            view.mission_id,
            view.status.as_str()
        ),
        _ => Ok(()),
    }
}

/// The progress bar for people; hidden for scripts.
fn bar(prefix: &str, json: bool) -> ProgressBar {
    if json {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(STEPS);
    let style = ProgressStyle::with_template("{spinner} {prefix} [{bar:40}] {percent:>3}% {msg} ({elapsed})")
        .map(|s| s.progress_chars("=> "))
        .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    bar.set_prefix(prefix.to_owned());
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    bar
}

fn position(progress: f64) -> u64 {
    (progress.clamp(0.0, 1.0) * STEPS as f64).round() as u64
}
