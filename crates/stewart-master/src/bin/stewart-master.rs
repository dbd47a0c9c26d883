//! `stewart-master run SYSTEM.ssp ...`: see `stewart_master::cli::USAGE`.

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    std::process::exit(stewart_master::cli::main(&args));
}
