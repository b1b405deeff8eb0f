//! The `propid` binary: parses the command line and hands over to [`propid::cli`].

use clap::{Parser, Subcommand};
use propid::cli;

/// Identify the dynamics of a motor + propeller on a thrust stand.
#[derive(Debug, Parser)]
#[command(name = "propid", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run the daemon against the built-in simulated stand for ~10 s and print the models.
    Demo(cli::demo::Args),
    /// Identify a model from a recording or CSV file.
    Identify(cli::identify::Args),
    /// Reproduce the ERA derivation on a simulated mass-spring-damper.
    Walkthrough(cli::walkthrough::Args),
    /// Run the simulated stand on a pseudo-terminal, or write a recording.
    Sim(cli::sim::Args),
    /// Run the identification daemon against a stand.
    Run(cli::run::Args),
    /// Replay a recording through the daemon's decoder and worker.
    Replay(cli::replay::Args),
    /// Show what the 2nd-order model gets wrong, name the cause, extend the model.
    Diagnose(cli::diagnose::Args),
    /// Serve one page of every stand publishing to an MQTT broker.
    Fleet(cli::fleet::Args),
    /// Score a saved model on another record: free-run simulation, RMS and fit per output.
    Compare(cli::model_file::CompareArgs),
    /// Simulate a saved model on a file's input (CSV out).
    Simulate(cli::model_file::SimulateArgs),
    /// The parameters a flight controller or simulator takes, from a saved model.
    Params(cli::model_file::ParamsArgs),
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Demo(a) => cli::demo::run(a),
        Command::Identify(a) => cli::identify::run(a),
        Command::Walkthrough(a) => cli::walkthrough::run(a),
        Command::Sim(a) => cli::sim::run(a),
        Command::Run(a) => cli::run::run(a),
        Command::Replay(a) => cli::replay::run(a),
        Command::Diagnose(a) => cli::diagnose::run(a),
        Command::Fleet(a) => cli::fleet::run(a),
        Command::Compare(a) => cli::model_file::compare(a),
        Command::Simulate(a) => cli::model_file::simulate(a),
        Command::Params(a) => cli::model_file::params(a),
    };
    if let Err(e) = result {
        if e.is_closed_pipe() {
            // the reader of stdout went away: it has what it wanted (as coreutils do)
            std::process::exit(0);
        }
        eprintln!("propid: {e}");
        std::process::exit(e.exit_code());
    }
}
