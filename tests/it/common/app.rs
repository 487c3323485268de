//! The app's options for a simulated droid as the whole-app tests start it: the default
//! configuration, no log file, nothing remembered, no tripod at connect.

#![allow(dead_code)]

use droidctl::app::run::AppOptions;
use droidctl::config::Config;
use droidctl::model::Model;
use droidctl::teleop::held::ReleaseMode;

/// `model`'s options, named as `--sim` names it.
pub fn simulated_options(model: Model) -> AppOptions {
    AppOptions {
        config: Config::defaults(),
        model,
        droid_name: format!("{} (simulated)", model.display_name()),
        log_path: None,
        release: ReleaseMode::Reported,
        tripod_on_connect: false,
        samples: None,
        remember: None,
    }
}
