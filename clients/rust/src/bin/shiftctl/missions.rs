//! `mission create|show|assign|replan|join|cancel` and `coverage SITE [--png FILE]`.

use std::collections::HashSet;

use shift_client::Client;
use shift_client::proto::MissionRequest;

use crate::cli::{CoverageArgs, MissionAction, MissionCreateArgs};
use crate::input::{bad, planner, robot};
use crate::{show, watch};

/// `mission …`.
pub async fn mission(client: &Client, action: MissionAction, json: bool) -> anyhow::Result<()> {
    let view = match action {
        MissionAction::Create(args) => return create(client, args, json).await,
        MissionAction::Show { id } => client.mission(&id).await?,
        MissionAction::Assign { id } => client.assign_mission(&id).await?,
        MissionAction::Replan { id } => client.replan_mission(&id).await?,
        MissionAction::Join { id, robot: text } => client.join_mission(&id, &robot("--robot", &text)?).await?,
        MissionAction::Cancel { id } => client.cancel_mission(&id).await?,
    };
    if json {
        show::json(&view)
    } else {
        print!("{}", show::mission(&view));
        Ok(())
    }
}

/// The request `mission create` sends; robot ids checked unique here (the daemon checks the rest).
fn request(args: &MissionCreateArgs) -> anyhow::Result<MissionRequest> {
    let robots = args
        .robots
        .iter()
        .map(|text| robot("--robot", text))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let mut seen = HashSet::new();
    if let Some(twice) = robots.iter().find(|r| !seen.insert(r.id.as_str())) {
        return Err(bad(format!("--robot: {} is named twice", twice.id)));
    }
    if robots.len() > MissionRequest::MAX_ROBOTS {
        return Err(bad(format!(
            "--robot: {} robots, at most {} in one mission",
            robots.len(),
            MissionRequest::MAX_ROBOTS
        )));
    }
    let (attribute, options, objective) = planner(&args.planner)?;
    Ok(MissionRequest {
        site: args.site.clone(),
        robots,
        attribute,
        options,
        objective,
    })
}

async fn create(client: &Client, args: MissionCreateArgs, json: bool) -> anyhow::Result<()> {
    let req = request(&args)?;
    let accepted = client.create_mission(&req).await?;
    if args.watch {
        return watch::follow_mission(client, &accepted.mission_id, json).await;
    }
    if json {
        show::json(&accepted)
    } else {
        println!("mission {} {}", accepted.mission_id, accepted.status.as_str());
        Ok(())
    }
}

/// `coverage SITE [--png FILE]`.
pub async fn coverage(client: &Client, args: CoverageArgs, json: bool) -> anyhow::Result<()> {
    let Some(out) = &args.png else {
        let grid = client.site_coverage(&args.site).await?;
        if json {
            return show::json(&grid);
        }
        print!("{}", show::coverage(&args.site, &grid));
        return Ok(());
    };
    let png = client.site_coverage_png(&args.site).await?;
    let (w, h) = image::load_from_memory_with_format(&png, image::ImageFormat::Png)
        .map(|img| (img.width(), img.height()))
        .map_err(|e| anyhow::anyhow!("the daemon's PNG does not decode: {e}"))?;
    std::fs::write(out, &png).map_err(|e| bad(format!("--png {}: {e}", out.display())))?;
    if json {
        show::json(
            &serde_json::json!({"file": out, "site": args.site, "width": w, "height": h,
            "bytes": png.len()}),
        )
    } else {
        println!("wrote {} ({w} × {h} px, site {})", out.display(), args.site);
        Ok(())
    }
}
