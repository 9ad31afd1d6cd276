//! From the command line to a scenario: the patient file (or the Table 2 plane) and the request
//! the flags make, placed by the planning front door (tissue-planner).

use tissue_planner::{Patient, Scenario};

use crate::cli::Cli;
use crate::failure::Failure;

/// Everything from the command line: the patient in cm, the placement, the job.
pub fn scenario(cli: &Cli) -> Result<Scenario, Failure> {
    let request = cli.request();
    // The numbers are checked before the file is read: a typo costs no load.
    request.check().map_err(|e| Failure::from_plan(&e))?;
    if let Some(volumes) = &cli.sweep {
        tissue_planner::check_sweep(volumes).map_err(|e| Failure::from_plan(&e))?;
    }
    if let Some(target) = cli.target_gain {
        tissue_planner::check_search(target, cli.bracket, cli.gain_tolerance, cli.volume)
            .map_err(|e| Failure::from_plan(&e))?;
    }
    let patient = match &cli.mesh {
        Some(path) => Patient::read(path, cli.unit()),
        None => Patient::table2(),
    }
    .map_err(|e| Failure::from_plan(&e))?;
    Scenario::new(patient, request).map_err(|e| Failure::from_plan(&e))
}
