//! The golden reports through the studio's job socket: each golden job, sent as the page sends
//! it (the typed messages of `tissue_studio::messages`), finishes with the golden report
//! (volatile fields masked), as `insert --job` and the C ABI do for the same job.

use std::time::Duration;

use futures_util::{SinkExt, StreamExt};
use tissue_planner::{golden, JobSpec};
use tissue_studio::messages::{ClientMessage, JobMessage, RunMessage};
use tokio_tungstenite::tungstenite::Message;

type Result<T = ()> = std::result::Result<T, Box<dyn std::error::Error>>;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_golden_job_gives_the_golden_report_over_the_socket() -> Result {
    let (studio, addr, server) = crate::serve().await?;
    let table2 = tissue_planner::Patient::shipped(tissue_planner::Shipped::Table2)?;
    let scan = tissue_cases::Scan::of_mesh(&table2, "table2")?;
    let patient = studio.add_patient(table2, scan, "Table 2".to_owned());
    let (mut tab, _) = tokio_tungstenite::connect_async(format!("ws://{addr}/api/ws")).await?;
    for name in golden::JOBS {
        let (_, text) = golden::job(name)?;
        let spec: JobSpec = serde_json::from_str(&text)?;
        let run = ClientMessage::Run(Box::new(RunMessage {
            patient: patient.clone(),
            spec,
        }));
        tab.send(Message::Text(serde_json::to_string(&run)?.into()))
            .await?;
        let report = loop {
            let message = tokio::time::timeout(Duration::from_secs(600), tab.next())
                .await?
                .ok_or("the socket closed")??;
            let Message::Text(text) = message else {
                continue;
            };
            match serde_json::from_str::<JobMessage>(&text)? {
                JobMessage::Finished { report, .. } => break report,
                JobMessage::Accepted { .. } | JobMessage::Progress { .. } => {}
                other => return Err(format!("{name}: {other:?}").into()),
            }
        };
        golden::check(name, &report.to_string())?;
    }
    studio.shutdown();
    server.abort();
    Ok(())
}
