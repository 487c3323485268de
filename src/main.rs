//! The `droidctl` binary: parse the command line and hand over to [`droidctl::cli`].

fn main() {
    std::process::exit(droidctl::cli::main());
}
