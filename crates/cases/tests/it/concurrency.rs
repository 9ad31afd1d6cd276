//! Saves at once from two threads on one handle and from two handles on one folder.

use std::collections::BTreeSet;

use tissue_cases::Library;

use crate::common::{save, table2, table2_single, Tmp};

fn uids(lib: &Library) -> BTreeSet<String> {
    lib.patients(None)
        .unwrap()
        .iter()
        .flat_map(|p| lib.plans(&p.uid).unwrap())
        .map(|c| c.uid)
        .collect()
}

#[test]
fn two_threads_on_one_handle_and_two_handles_on_one_folder_lose_nothing() {
    let tmp = Tmp::new("threads");
    let (_, scan) = table2();
    let (spec, finished) = table2_single(100.0, 40);
    let one = Library::open(&tmp.lib_dir()).unwrap();
    // Two threads, one Library (Send + Sync).
    let saved: Vec<String> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..2)
            .map(|t| {
                let (one, scan, spec, finished) = (&one, &scan, &spec, &finished);
                s.spawn(move || {
                    (0..10)
                        .map(|i| save(one, scan, &format!("t{t} #{i}"), spec, finished).uid)
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().unwrap())
            .collect()
    });
    assert_eq!(saved.len(), 20);
    assert_eq!(uids(&one), saved.iter().cloned().collect());
    // Two handles on one folder, each on its own thread.
    let more: Vec<String> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..2)
            .map(|t| {
                let (dir, scan, spec, finished) = (tmp.lib_dir(), &scan, &spec, &finished);
                s.spawn(move || {
                    let lib = Library::open(&dir).unwrap();
                    (0..10)
                        .map(|i| save(&lib, scan, &format!("h{t} #{i}"), spec, finished).uid)
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().unwrap())
            .collect()
    });
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
