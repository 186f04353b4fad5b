use clap::Parser;

fn main() {
    let cli = wavemill::cli::Cli::parse();
    std::process::exit(wavemill::cli::run(cli));
}
