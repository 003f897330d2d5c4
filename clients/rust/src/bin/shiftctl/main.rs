//! `shiftctl`: SHIFT's operator and backend command line over `shift-client`. Human output by default,
//! `--json` for scripts; exit codes 0 ok, 1 the server said no (or was not reached), 2 bad input.

mod cli;
mod commands;
mod export;
mod input;
mod missions;
mod render;
mod show;
mod tail;
mod watch;

use std::process::ExitCode;

use clap::Parser;
use shift_client::{Client, ClientError};

use cli::{Cli, Command};
use input::BadInput;

fn main() -> ExitCode {
    // clap exits with 2 on a usage error (0 for --help / --version).
    let cli = Cli::parse();
    let json = cli.json;
    let runtime = match tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
    {
        Ok(r) => r,
        Err(e) => {
            eprintln!("shiftctl: starting the runtime: {e}");
            return ExitCode::from(1);
        }
    };
    match runtime.block_on(run(cli)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            report(&e, json);
            ExitCode::from(exit_code(&e))
        }
    }
}

async fn run(cli: Cli) -> anyhow::Result<()> {
    let client = Client::new(&cli.http)
        .map_err(|e| BadInput(format!("--http: {e}")))?
        .with_token(cli.token.clone().unwrap_or_default());
    let json = cli.json;
    match cli.command {
        Command::Site { action } => commands::site(&client, action, json).await,
        Command::Sites => commands::sites(&client, json).await,
        Command::Plan(args) => commands::plan(&client, args, json).await,
        Command::Plans(args) => commands::plans(&client, args, json).await,
        Command::Export(args) => export::run(&client, args).await,
        Command::Render(args) => render::run(&client, args, json).await,
        Command::Mission { action } => missions::mission(&client, action, json).await,
        Command::Coverage(args) => missions::coverage(&client, args, json).await,
        Command::Robots => commands::robots(&client, json).await,
        Command::Tail { stream } => tail::run(stream, json).await,
    }
}

/// 2 for bad input (ours or the client's refusal before sending), 1 for everything else.
fn exit_code(e: &anyhow::Error) -> u8 {
    if e.downcast_ref::<BadInput>().is_some() {
        return 2;
    }
    match e.downcast_ref::<ClientError>() {
        Some(ClientError::InvalidInput(_)) => 2,
        _ => 1,
    }
}

fn report(e: &anyhow::Error, json: bool) {
    if json && let Some(ClientError::Api { status, error, .. }) = e.downcast_ref::<ClientError>() {
        let body = serde_json::json!({"status": status.as_u16(), "error": error});
        eprintln!("{body}");
        return;
    }
    eprintln!("shiftctl: {e:#}");
}
