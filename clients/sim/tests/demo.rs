//! `shiftd demo` (issue 19's one command) runs the whole loop: the daemon with the demo site, three simulated
//! robots each on its band, a box the daemon does not know in the hall. Every robot finishes, none touches the
//! hidden world, the hall robot is corrected round the box, and the fleet sweeps the site.

use anyhow::{Context, Result, ensure};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_demo_closes_the_fleet_loop() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let report = shiftd::demo::run(shiftd::demo::DemoArgs {
        bind: "127.0.0.1:0".parse()?,
        sim: env!("CARGO_BIN_EXE_shift-sim").into(),
        speedup: 25.0,
        dir: dir.path().to_path_buf(),
    })
    .await?;
    eprintln!("{}", shiftd::demo::table(&report));
    let robots = report["robots"].as_array().context("robots")?;
    ensure!(robots.len() == 3, "three robots: {report}");
    for r in robots {
        ensure!(r["finished"] == true, "{} did not finish: {r}", r["id"]);
        ensure!(r["collisions"] == 0, "{} touched the hidden world: {r}", r["id"]);
    }
    let hall = robots.iter().find(|r| r["id"] == "hall").context("hall robot")?;
    ensure!(
        hall["corrections_applied"].as_u64().unwrap_or(0) >= 1,
        "the box in the hall got no correction: {hall}"
    );
    let covered = report["fleet"]["covered_pct"].as_f64().context("fleet covered")?;
    ensure!(covered >= 95.0, "the fleet swept {covered:.1} % of the demo site");
    Ok(())
}
