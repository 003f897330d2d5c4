//! The commands that are one or two API calls: sites, plans (submit, show, cancel, assign, list), robots.

use std::path::Path;

use anyhow::Context as _;
use shift_client::Client;
use shift_client::proto::{FieldRequest, PlanListQuery, PlanRequest, RobotSpec};

use crate::cli::{PlanAction, PlanArgs, PlansArgs, SiteAction};
use crate::input::{bad, planner, point, polygon, positive, status};
use crate::{show, watch};

/// `site upload|show`.
pub async fn site(client: &Client, action: SiteAction, json: bool) -> anyhow::Result<()> {
    let summary = match action {
        SiteAction::Upload { site, yaml } => {
            let (text, image, name) = read_map(&yaml)?;
            client.upload_map(&site, text, image, &name).await?
        }
        SiteAction::Field {
            site,
            geojson,
            no_go,
            tool_width,
            resolution_m,
        } => {
            let request = FieldRequest {
                field: read_geojson("--geojson", &geojson)?,
                no_go: no_go
                    .iter()
                    .map(|p| read_geojson("--no-go", p))
                    .collect::<anyhow::Result<_>>()?,
                resolution_m,
                tool_width,
            };
            client.upload_field(&site, &request).await?
        }
        SiteAction::Show { site } => client.site(&site).await?,
    };
    if json {
        show::json(&summary)
    } else {
        print!("{}", show::site(&summary));
        Ok(())
    }
}

/// Reads a map_server YAML and the image its `image` key names (relative to the YAML).
/// A GeoJSON file, read as JSON (the daemon checks its shape and names what is wrong).
fn read_geojson(flag: &str, path: &Path) -> anyhow::Result<serde_json::Value> {
    let text = std::fs::read_to_string(path).map_err(|e| bad(format!("{flag} {}: {e}", path.display())))?;
    serde_json::from_str(&text).map_err(|e| bad(format!("{flag} {}: not JSON: {e}", path.display())))
}

fn read_map(yaml_path: &Path) -> anyhow::Result<(String, Vec<u8>, String)> {
    let text = std::fs::read_to_string(yaml_path).map_err(|e| bad(format!("--yaml {}: {e}", yaml_path.display())))?;
    let doc: serde_yaml_ng::Value =
        serde_yaml_ng::from_str(&text).map_err(|e| bad(format!("--yaml {}: {e}", yaml_path.display())))?;
    let image = doc
        .get("image")
        .and_then(|v| v.as_str())
        .ok_or_else(|| bad(format!("--yaml {}: no `image` key", yaml_path.display())))?;
    let image_path = yaml_path.parent().unwrap_or(Path::new(".")).join(image);
    let bytes = std::fs::read(&image_path).map_err(|e| bad(format!("map image {}: {e}", image_path.display())))?;
    let name = image_path
        .file_name()
        .map_or_else(|| "map".into(), |n| n.to_string_lossy().into_owned());
    Ok((text, bytes, name))
}

/// `sites`.
pub async fn sites(client: &Client, json: bool) -> anyhow::Result<()> {
    let list = client.sites().await?;
    if json {
        show::json(&list)
    } else {
        print!("{}", show::sites(&list.items));
        Ok(())
    }
}

/// `plan …`.
pub async fn plan(client: &Client, args: PlanArgs, json: bool) -> anyhow::Result<()> {
    let status = match args.action {
        Some(PlanAction::Show { id }) => client.plan(&id).await?,
        Some(PlanAction::Cancel { id }) => client.cancel_plan(&id).await?,
        Some(PlanAction::Assign { id, robot }) => client.assign(&id, &robot).await?,
        None => return submit(client, args, json).await,
    };
    if json {
        show::json(&status)
    } else {
        print!("{}", show::plan(&status));
        Ok(())
    }
}

fn request(args: &PlanArgs) -> anyhow::Result<PlanRequest> {
    let site = args.site.clone().ok_or_else(|| bad("--site is required"))?;
    // With --start-wgs84 the daemon fills the start in; this one is not sent.
    let start = match (&args.start, &args.start_wgs84) {
        (Some(s), _) => point("--start", s)?,
        (None, Some(_)) => [0.0, 0.0],
        (None, None) => return Err(bad("give --start X,Y or --start-wgs84 LON,LAT")),
    };
    let region = args.region.as_deref().map(|r| polygon("--region", r)).transpose()?;
    for (name, v) in [
        ("--robot-radius", args.robot_radius),
        ("--tool-width", args.tool_width),
        ("--v-min", args.v_min),
        ("--v-max", args.v_max),
        ("--a-max", args.a_max),
    ] {
        positive(name, v)?;
    }
    let (attribute, options, objective) = planner(&args.planner)?;
    Ok(PlanRequest {
        site,
        start,
        robot: RobotSpec {
            radius: args.robot_radius,
            footprint: None,
            tool_width: args.tool_width,
            v_min: args.v_min,
            v_max: args.v_max,
            a_max: args.a_max,
        },
        attribute,
        region,
        options,
        objective,
        snap_start_m: args.snap_start_m,
    })
}

async fn submit(client: &Client, args: PlanArgs, json: bool) -> anyhow::Result<()> {
    let req = request(&args)?;
    let accepted = match &args.start_wgs84 {
        Some(ll) => client.create_plan_wgs84(&req, point("--start-wgs84", ll)?).await?,
        None => client.create_plan(&req).await?,
    };
    if args.watch {
        return watch::follow(client, &accepted.plan_id, json).await;
    }
    if json {
        show::json(&accepted)
    } else {
        println!("plan {} {}", accepted.plan_id, accepted.status.as_str());
        Ok(())
    }
}

/// `plans`.
pub async fn plans(client: &Client, args: PlansArgs, json: bool) -> anyhow::Result<()> {
    let query = PlanListQuery {
        site: args.site,
        status: args.status.as_deref().map(status).transpose()?,
        robot: args.robot,
        limit: args.limit,
        after: args.after,
    };
    if let Some(l) = query.limit
        && !(1..=shift_client::proto::PLAN_PAGE_MAX).contains(&l)
    {
        return Err(bad(format!(
            "--limit: {l} is outside 1..={}",
            shift_client::proto::PLAN_PAGE_MAX
        )));
    }
    let page = if args.all {
        shift_client::proto::PlanList {
            items: client.all_plans(query).await?,
            next: None,
        }
    } else {
        client.plans(&query).await?
    };
    if json {
        return show::json(&page);
    }
    print!("{}", show::plans(&page.items));
    if let Some(next) = &page.next {
        println!("more: --after {next}");
    }
    Ok(())
}

/// `robots`.
pub async fn robots(client: &Client, json: bool) -> anyhow::Result<()> {
    let list = client.robots().await.context("listing robots")?;
    if json {
        show::json(&list)
    } else {
        print!("{}", show::robots(&list));
        Ok(())
    }
}
