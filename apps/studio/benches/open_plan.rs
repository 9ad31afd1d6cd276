//! Issue 33's bar: opening a stored plan of a 160k-triangle scan takes at most 200 ms. Measured
//! is the whole answer of `GET /api/cases/plans/{uid}` through the studio's router
//! (`tower::ServiceExt::oneshot`, the access guard included): the library's read of the plan
//! (its report, job and result blob, decoded) and the JSON the page gets (the patient's mesh in
//! cm, the patient after and its fields), collected to the last byte.
//!
//! The scan is `tissue_mesh::grid(284, 20.0)`: a 20 cm plane of 284 × 284 vertices,
//! 2 · 283² = 160,178 triangles, in cm. The set-up runs a 5-step plan on it at its centre through
//! the planner's front door and saves it in a case library in a temporary folder (removed at the
//! end); the run's result covers every vertex, as a full run's does.
//!
//! ```sh
//! cargo bench -p tissue-studio --bench open_plan
//! ```
#![allow(clippy::expect_used, clippy::print_stderr)]

use std::time::Duration;

use axum::body::Body;
use axum::http::{Request, StatusCode};
use criterion::{criterion_group, criterion_main, Criterion};
use http_body_util::BodyExt;
use tissue_cases::{NewPlan, Scan};
use tissue_planner::{CancelToken, JobSpec, Patient, PlanRequest, Scenario, Tool, Unit};
use tissue_studio::{Access, Limits, Studio};
use tower::ServiceExt;

/// The bar of the issue.
const BAR: Duration = Duration::from_millis(200);

fn open_plan(c: &mut Criterion) {
    let data = std::env::temp_dir().join(format!("tissue-open-plan-bench-{}", std::process::id()));
    let studio = Studio::with_data(Limits::default(), &data).expect("the library");
    let mesh = tissue_mesh::grid(284, 20.0).expect("the grid");
    let triangles = mesh.triangles().len();
    let patient = Patient::from_mesh(mesh, Unit::Cm, "grid284.obj".to_owned()).expect("patient");
    let scan = Scan::of_mesh(&patient, "grid284").expect("scan");
    let spec = JobSpec {
        request: PlanRequest {
            at: Some([0.0, 0.0, 0.0]),
            max_steps: 5,
            ..PlanRequest::default()
        },
        ..JobSpec::default()
    };
    let scenario = Scenario::new(patient, spec.request.clone()).expect("scenario");
    let finished = spec
        .plan(&scenario)
        .expect("plan")
        .run(&scenario, Tool::Studio, &CancelToken::new(), |_| {})
        .expect("the run");
    let plan = NewPlan {
        name: "bench",
        note: "",
        spec: &spec,
        finished: &finished,
    };
    let info = studio
        .library()
        .save(&scan, Some("grid 284"), plan)
        .expect("saved");
    let app = tissue_studio::router(studio.clone(), Access::loopback(8000));
    let runtime = tokio::runtime::Runtime::new().expect("runtime");
    let uri = format!("/api/cases/plans/{}", info.uid);
    let get = || async {
        let response = app
            .clone()
            .oneshot(
                Request::get(&uri)
                    .header("host", "127.0.0.1:8000")
                    .body(Body::empty())
                    .expect("request"),
            )
            .await
            .expect("answer");
        assert_eq!(response.status(), StatusCode::OK);
        response
            .into_body()
            .collect()
            .await
            .expect("body")
            .to_bytes()
            .len()
    };
    let bytes = runtime.block_on(get());
    eprintln!(
        "open_plan: a {triangles}-triangle scan's plan, {:.1} MB of JSON; the bar is {BAR:?}",
        bytes as f64 / 1e6
    );
    let mut group = c.benchmark_group("open_plan");
    group.sample_size(10);
    group.bench_function("get_plan_160k_triangles", |b| {
        b.iter(|| runtime.block_on(get()));
    });
    group.finish();
    studio.shutdown();
    let _ = std::fs::remove_dir_all(&data);
}

criterion_group!(benches, open_plan);
criterion_main!(benches);
