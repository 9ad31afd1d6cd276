//! From the command line to a scenario: the patient file (or the Table 2 plane) and the job's
//! request, placed by the planning front door (tissue-planner).

use tissue_planner::{JobSpec, Patient, Scenario};

use crate::cli::Cli;
use crate::failure::{Failure, FromPlan};

/// The patient in cm and the placement of `spec`'s request.
pub fn scenario(cli: &Cli, spec: &JobSpec) -> Result<Scenario, Failure> {
    let patient = match &cli.mesh {
        Some(path) => Patient::read(path, cli.unit()),
        None => Patient::table2(),
    }
    .map_err(|e| Failure::from_plan(&e))?;
    Scenario::new(patient, spec.request.clone()).map_err(|e| Failure::from_plan(&e))
}
