//! The `droidctl` binary: parse the command line and hand over to [`droidctl::cli`].

fn main() {
    // droidctl started as a Sphero Edu program's engine (src/edu/child.rs): before anything
    // else, so the child sets up nothing it does not need (no logging, no signals).
    let mut args = std::env::args_os().skip(1);
    if args.next().as_deref() == Some(std::ffi::OsStr::new(droidctl::edu::child::ENGINE_ARG)) {
        let rest: Vec<String> = args
            .take(1)
            .map(|a| a.to_string_lossy().into_owned())
            .collect();
        std::process::exit(droidctl::edu::child::serve(&rest));
    }
    std::process::exit(droidctl::cli::main());
}
