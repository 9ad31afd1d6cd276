//! Saves at once from two threads on one handle and from two handles on one folder.

use std::collections::BTreeSet;

use tissue_cases::{Library, Scan};
use tissue_planner::{Finished, JobSpec};

use crate::common::{save, table2, table2_single, Tmp};

fn uids(lib: &Library) -> BTreeSet<String> {
    lib.patients(None)
        .unwrap()
        .iter()
        .flat_map(|p| lib.plans(&p.uid).unwrap())
        .map(|c| c.uid)
        .collect()
}

/// Ten saves on each of `libs`, on two threads at once: the uids saved.
fn ten_each(
    libs: [&Library; 2],
    tag: &str,
    scan: &Scan,
    spec: &JobSpec,
    finished: &Finished,
) -> Vec<String> {
    std::thread::scope(|s| {
        let workers: Vec<_> = libs
            .into_iter()
            .enumerate()
            .map(|(t, lib)| {
                s.spawn(move || {
                    (0..10)
                        .map(|i| save(lib, scan, &format!("{tag} {t} #{i}"), spec, finished).uid)
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().unwrap())
            .collect()
    })
}

#[test]
fn two_threads_on_one_handle_and_two_handles_on_one_folder_lose_nothing() {
    let tmp = Tmp::new("threads");
    let (_, scan) = table2();
    let (spec, finished) = table2_single(100.0, 40);
    // Two threads, one Library (Send + Sync).
    let one = Library::open(&tmp.lib_dir()).unwrap();
    let saved = ten_each([&one, &one], "thread", &scan, &spec, &finished);
    assert_eq!(saved.len(), 20);
    assert_eq!(uids(&one), saved.iter().cloned().collect());
    // Two handles on one folder, each on its own thread.
    let (h0, h1) = (
        Library::open(&tmp.lib_dir()).unwrap(),
        Library::open(&tmp.lib_dir()).unwrap(),
    );
    let more = ten_each([&h0, &h1], "handle", &scan, &spec, &finished);
    assert_eq!(more.len(), 20);
    let all: BTreeSet<String> = saved.into_iter().chain(more).collect();
    assert_eq!(all.len(), 40);
    let reopened = Library::open(&tmp.lib_dir()).unwrap();
    assert_eq!(uids(&reopened), all);
    assert_eq!(reopened.patients(None).unwrap().len(), 1);
    assert_eq!(reopened.integrity_check().unwrap(), "ok");
}

#[test]
fn first_opens_racing_on_a_new_folder_all_succeed() {
    let tmp = Tmp::new("race");
    let dir = tmp.lib_dir();
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..4)
            .map(|_| s.spawn(|| Library::open(&dir).map(|_| ())))
            .collect();
        for h in handles {
            h.join().unwrap().unwrap();
        }
    });
    assert_eq!(
        Library::open(&dir).unwrap().integrity_check().unwrap(),
        "ok"
    );
}
