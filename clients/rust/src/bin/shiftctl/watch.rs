//! `plan … --watch`: follows the plan's server-sent events — a progress bar (regions counted as they stream)
//! for people, one JSON event per line for scripts — then prints the final status with its metrics.

use indicatif::{ProgressBar, ProgressStyle};
use shift_client::Client;
use shift_client::proto::{PlanEvent, PlanStatus, PlanStatusResponse};

use crate::show;

/// Steps of the bar (progress is 0-1).
const STEPS: u64 = 1000;

/// Follows `plan_id` until its computation ended; an error when it failed or was cancelled.
pub async fn follow(client: &Client, plan_id: &str, json: bool) -> anyhow::Result<()> {
    let mut events = client.events(plan_id).await?;
    let bar = if json {
        ProgressBar::hidden()
    } else {
        let bar = ProgressBar::new(STEPS);
        let style = ProgressStyle::with_template("{spinner} {prefix} [{bar:40}] {percent:>3}% {msg} ({elapsed})")
            .map(|s| s.progress_chars("=> "))
            .unwrap_or_else(|_| ProgressStyle::default_bar());
        bar.set_style(style);
        bar.set_prefix(plan_id.to_owned());
        bar.enable_steady_tick(std::time::Duration::from_millis(120));
        bar
    };
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

fn position(progress: f64) -> u64 {
    (progress.clamp(0.0, 1.0) * STEPS as f64).round() as u64
}
