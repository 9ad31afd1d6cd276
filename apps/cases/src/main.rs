//! `tissue-cases`: the case library (tissue-cases) from the command line.
//!
//! A thin shell: the command line ([`cli`]) names a subcommand; the library is opened
//! ([`ids`]: made only by the commands that write, ids resolved from a unique beginning), the
//! library call made, and its answer printed ([`text`]: the tables, the `--json` shapes). Every
//! failure is one line on stderr and a documented exit code ([`failure`]); see
//! `tissue-cases --help`, `apps/cases/README.md` and `docs/cases.md`.
#![allow(clippy::print_stdout, clippy::print_stderr)]

mod cli;
mod failure;
mod ids;
mod text;

use std::io::Write;
use std::process::ExitCode;

use clap::Parser;
use tissue_cases::Library;

use crate::cli::{Cli, Command};
use crate::failure::{from_case, Exit, Failure};
use crate::ids::Kind;
use crate::text::{PatientEntry, PlanEntry};

/// Writes `text` to stdout as it is (a report byte for byte).
fn out(text: &str) -> Result<(), Failure> {
    let mut stdout = std::io::stdout().lock();
    stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
        .map_err(|e| Failure::output("standard output", e))
}

/// The most of a file `import` reads: more than any archive the library takes (it bounds them
/// again, and tighter), so that a wrong file is not read whole into memory.
const MAX_IMPORT_BYTES: u64 = 1 << 30;

/// The archive to import, read up to [`MAX_IMPORT_BYTES`].
fn read_archive(path: &std::path::Path) -> Result<Vec<u8>, Failure> {
    use std::io::Read;
    let unreadable = |e: std::io::Error| {
        Failure::new(
            Exit::Input,
            format!("cannot read the case archive {}: {e}", path.display()),
        )
    };
    let file = std::fs::File::open(path).map_err(unreadable)?;
    let mut bytes = Vec::new();
    file.take(MAX_IMPORT_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(unreadable)?;
    if bytes.len() as u64 > MAX_IMPORT_BYTES {
        return Err(Failure::new(
            Exit::Input,
            format!(
                "{} is larger than {} MiB, so it is not a case archive: import a .zip made by \
                 `tissue-cases export`",
                path.display(),
                MAX_IMPORT_BYTES >> 20
            ),
        ));
    }
    Ok(bytes)
}

/// The library for a command that only reads, or the not-found error for `id`.
/// An id of the wrong kind is refused first, whether or not there is a library.
fn existing(dir: &std::path::Path, kind: Kind, id: &str) -> Result<Library, Failure> {
    ids::expect(id, kind)?;
    ids::open_existing(dir)?.ok_or_else(|| ids::not_found(kind, id))
}

/// A patient with its plans.
fn entry(library: &Library, patient: tissue_cases::PatientInfo) -> Result<PatientEntry, Failure> {
    let plans = library.plans(&patient.uid).map_err(|e| from_case(&e))?;
    Ok(PatientEntry { patient, plans })
}

fn run(cli: &Cli) -> Result<(), Failure> {
    let dir = ids::data_dir(cli.data.as_deref())?;
    match &cli.command {
        Command::List { search, json } => {
            let entries = match ids::open_existing(&dir)? {
                None => Vec::new(),
                Some(library) => library
                    .patients(search.as_deref())
                    .map_err(|e| from_case(&e))?
                    .into_iter()
                    .map(|p| entry(&library, p))
                    .collect::<Result<Vec<_>, _>>()?,
            };
            if *json {
                out(&text::json(&entries))
            } else if entries.is_empty() {
                eprintln!(
                    "tissue-cases: no patients in {}{}",
                    dir.display(),
                    match search {
                        Some(s) => format!(" labelled with {s:?}"),
                        None => "; save a plan with `insert --save NAME`".to_owned(),
                    }
                );
                Ok(())
            } else {
                out(&text::list(&entries))
            }
        }
        Command::Show { id, json, report } => {
            let kind = ids::kind(id)?;
            let library = existing(&dir, kind, id)?;
            let uid = ids::resolve(&library, id, kind)?;
            match kind {
                Kind::Patient => {
                    if *report {
                        return Err(Failure::new(
                            Exit::Usage,
                            format!(
                                "--report prints a plan's report; {id} is a patient: show it \
                                 without --report to see its plans"
                            ),
                        ));
                    }
                    let patient = library.patient(&uid).map_err(|e| from_case(&e))?;
                    let e = entry(&library, patient)?;
                    out(&if *json {
                        text::json(&e)
                    } else {
                        text::patient(&e)
                    })
                }
                Kind::Plan => {
                    let plan = library.open_plan(&uid).map_err(|e| from_case(&e))?;
                    if *report {
                        out(&plan.report_json)
                    } else if *json {
                        out(&text::json(&PlanEntry::of(&plan)))
                    } else {
                        out(&text::plan(&plan))
                    }
                }
            }
        }
        Command::Export { patient, out: path } => {
            let library = existing(&dir, Kind::Patient, patient)?;
            let uid = ids::resolve(&library, patient, Kind::Patient)?;
            let info = library.patient(&uid).map_err(|e| from_case(&e))?;
            library
                .export_case_to(&uid, path)
                .map_err(|e| from_case(&e))?;
            eprintln!(
                "tissue-cases: wrote {} (patient {} {:?}, {} plans)",
                path.display(),
                info.uid,
                info.label,
                info.plans
            );
            Ok(())
        }
        Command::Import { file, json } => {
            let bytes = read_archive(file)?;
            let library = ids::open(&dir)?;
            let summary = library.import_case(&bytes).map_err(|e| from_case(&e))?;
            out(&if *json {
                text::json(&summary)
            } else {
                text::import(&summary)
            })
        }
        Command::Rename { id, name } => {
            let kind = ids::kind(id)?;
            let library = existing(&dir, kind, id)?;
            let uid = ids::resolve(&library, id, kind)?;
            match kind {
                Kind::Plan => {
                    let plan = library.rename_plan(&uid, name).map_err(|e| from_case(&e))?;
                    eprintln!("tissue-cases: renamed plan {} to {:?}", plan.uid, plan.name);
                }
                Kind::Patient => {
                    let patient = library
                        .rename_patient(&uid, name)
                        .map_err(|e| from_case(&e))?;
                    eprintln!(
                        "tissue-cases: relabelled patient {} {:?}",
                        patient.uid, patient.label
                    );
                }
            }
            Ok(())
        }
        Command::Note { plan, text } => {
            let library = existing(&dir, Kind::Plan, plan)?;
            let uid = ids::resolve(&library, plan, Kind::Plan)?;
            let info = library.set_note(&uid, text).map_err(|e| from_case(&e))?;
            eprintln!("tissue-cases: noted plan {} {:?}", info.uid, info.name);
            Ok(())
        }
        Command::Delete { plan } => {
            let library = existing(&dir, Kind::Plan, plan)?;
            let uid = ids::resolve(&library, plan, Kind::Plan)?;
            let info = library.plan(&uid).map_err(|e| from_case(&e))?;
            library.delete_plan(&uid).map_err(|e| from_case(&e))?;
            eprintln!(
                "tissue-cases: deleted plan {} {:?} of patient {}",
                info.uid, info.name, info.patient_uid
            );
            Ok(())
        }
        Command::Erase { patient, yes } => {
            let library = existing(&dir, Kind::Patient, patient)?;
            let uid = ids::resolve(&library, patient, Kind::Patient)?;
            let info = library.patient(&uid).map_err(|e| from_case(&e))?;
            let what = format!(
                "patient {} {:?}, {} and the scan {} ({} bytes)",
                info.uid,
                info.label,
                match info.plans {
                    1 => "its 1 plan".to_owned(),
                    n => format!("its {n} plans"),
                },
                info.scan_name,
                info.scan_bytes
            );
            if !*yes {
                return Err(Failure::new(
                    Exit::Usage,
                    format!(
                        "erase removes {what} from {} for good, overwritten in every file of \
                         the library; it cannot be undone. Nothing was erased: run again with \
                         --yes to erase (or `export` the case first)",
                        library.database_path().display()
                    ),
                ));
            }
            library.erase_patient(&uid).map_err(|e| from_case(&e))?;
            eprintln!("tissue-cases: erased {what}");
            Ok(())
        }
        Command::Check => {
            let Some(library) = ids::open_existing(&dir)? else {
                eprintln!(
                    "tissue-cases: no case library in {} (nothing to check)",
                    dir.display()
                );
                return out("ok\n");
            };
            let answer = library.integrity_check().map_err(|e| from_case(&e))?;
            out(&format!("{}\n", answer.trim_end()))?;
            if answer.trim() == "ok" {
                Ok(())
            } else {
                Err(Failure::new(
                    Exit::Output,
                    format!(
                        "the case library {} failed its integrity check; restore it from a \
                         backup (docs/cases.md) or export what still opens",
                        library.database_path().display()
                    ),
                ))
            }
        }
    }
}

fn main() -> ExitCode {
    // A closed stdout (`| head`) ends the program by SIGPIPE, silently; see tissue-cli.
    tissue_cli::reset_sigpipe();
    let cli = Cli::parse();
    match run(&cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(failure) => {
            let hint = if failure.code == Exit::Usage {
                " (see tissue-cases --help)"
            } else {
                ""
            };
            eprintln!("tissue-cases: error: {}{hint}", failure.line());
            ExitCode::from(failure.code)
        }
    }
}
