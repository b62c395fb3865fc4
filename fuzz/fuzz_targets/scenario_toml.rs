//! The TOML scenario loader on arbitrary text: a load error is fine, a panic
//! is not. What loads is validated, and a valid problem is planned for a few
//! steps.
#![no_main]

use std::path::Path;

use capp_fuzz::plan_a_few_steps;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(problem) = capp_sim::input::scenario_file::parse(text, Path::new("fuzz.toml")) else {
        return;
    };
    if let Ok(scenario) = problem.validate() {
        plan_a_few_steps(&scenario, &problem.start);
    }
});
