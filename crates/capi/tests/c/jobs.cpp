// C++17: a job cancelled from another thread in the middle of its run; a sweep and an inverse
// search (typed), and a sweep started from the planner's JSON.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "check.hpp"
#include "tissue.h"

namespace {


// Frees a handle at the end of its scope.
template <typename T, void (*Free)(T*)>
struct Owned {
    T* p = nullptr;
    Owned() = default;
    Owned(const Owned&) = delete;
    Owned& operator=(const Owned&) = delete;
    ~Owned() { Free(p); }
};
using Patient = Owned<tissue_patient, tissue_patient_free>;
using Job = Owned<tissue_job, tissue_job_free>;

}  // namespace

int main() {
    Patient plane;
    ok(tissue_patient_shipped(TISSUE_PATIENT_TABLE2, &plane.p), "patient");
    tissue_plan_options options;
    ok(tissue_plan_options_default(&options), "defaults");

    // --- Cancel from another thread once the run has taken 20 steps.
    {
        Job job;
        ok(tissue_plan_start(plane.p, &options, &job.p), "start");
        std::atomic<uint64_t> cancelled_at{0};
        std::thread canceller([&] {
            tissue_progress p{};
            while (tissue_job_progress(job.p, &p) == TISSUE_OK &&
                   p.state == TISSUE_JOB_RUNNING) {
                if (p.step >= 20) {
                    cancelled_at = p.step;
                    tissue_job_cancel(job.p);
                    return;
                }
                std::this_thread::sleep_for(std::chrono::milliseconds(1));
            }
        });
        const auto started = std::chrono::steady_clock::now();
        const tissue_status s = tissue_job_wait(job.p, -1.0);
        const double took =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
        canceller.join();
        const std::string message = last_error();
        tissue_progress p{};
        ok(tissue_job_progress(job.p, &p), "progress");
        std::printf("cancelled from another thread at step %llu: ended at step %llu of %llu "
                    "after %.2f s, status %d: %s\n",
                    static_cast<unsigned long long>(cancelled_at.load()),
                    static_cast<unsigned long long>(p.step),
                    static_cast<unsigned long long>(p.max_steps), took, static_cast<int>(s),
                    message.c_str());
        check(s == TISSUE_CANCELLED, "status " + std::to_string(s));
        check(p.state == TISSUE_JOB_CANCELLED, "state");
        check(cancelled_at >= 20 && p.step < 300, "stopped in the middle");
        check(message.find("cancelled") != std::string::npos, message);
        tissue_plan_result r{};
        check(tissue_job_result(job.p, &r) == TISSUE_CANCELLED, "no result");
    }

    // --- A sweep over two volumes: the gain rises with the volume.
    {
        Job job;
        const double volumes[] = {50.0, 150.0};
        ok(tissue_sweep_start(plane.p, &options, volumes, 2, &job.p), "sweep");
        ok(tissue_job_wait(job.p, -1.0), "sweep wait");
        size_t rows = 0;
        ok(tissue_job_sweep_count(job.p, &rows), "rows");
        check(rows == 2, "two rows");
        double gains[2] = {0, 0};
        for (size_t i = 0; i < rows && i < 2; ++i) {
            double v = 0;
            tissue_plan_result r{};
            ok(tissue_job_sweep_row(job.p, i, &v, &r), "row");
            gains[i] = r.area_gain_cm2;
            std::printf("sweep: %.0f cm3 -> gain %.2f cm2\n", v, r.area_gain_cm2);
        }
        // Table 2's bands: 11.49 and 57.16 cm² ± 25 %.
        check(gains[0] > 0.75 * 11.49 && gains[0] < 1.25 * 11.49, "50 cm3 gain");
        check(gains[1] > 0.75 * 57.16 && gains[1] < 1.25 * 57.16, "150 cm3 gain");
        tissue_plan_result r{};
        check(tissue_job_result(job.p, &r) == TISSUE_INVALID_ARGUMENT, "a sweep has rows");
    }

    // --- The inverse search: the volume for 35 cm² of new skin, between 80 and 130 cm³.
    {
        Job job;
        ok(tissue_inverse_start(plane.p, &options, 35.0, 80.0, 130.0, 2.0, &job.p), "inverse");
        ok(tissue_job_wait(job.p, -1.0), "inverse wait");
        tissue_inverse_result r{};
        ok(tissue_job_inverse_result(job.p, &r), "answer");
        std::printf("inverse: %.1f cm3 gives %.2f cm2 (target 35, %u runs, converged %d)\n",
                    r.volume_cm3, r.area_gain_cm2, r.runs, static_cast<int>(r.converged));
        check(r.converged && r.area_gain_cm2 > 33.0 && r.area_gain_cm2 < 37.0, "found");
        check(r.volume_cm3 > 80.0 && r.volume_cm3 < 130.0, "in the bracket");
    }

    // --- The same planner request as JSON: a short single run with a rotation and a step limit,
    // and a timeout while it runs.
    {
        Job job;
        ok(tissue_job_start_json(plane.p,
                                 R"({"mode": "single", "request": {"volume_cm3": 80,
                                     "rotation_deg": 30, "max_steps": 25}})",
                                 &job.p),
           "json");
        ok(tissue_job_wait(job.p, -1.0), "json wait");
        tissue_plan_result r{};
        ok(tissue_job_result(job.p, &r), "json result");
        check(r.steps == 25 && !r.settled, "25 steps");
        std::string report(1, '\0');
        size_t length = 0;
        check(tissue_job_report_json(job.p, report.data(), report.size(), &length) ==
                  TISSUE_BUFFER_TOO_SMALL,
              "query");
        report.resize(length);
        ok(tissue_job_report_json(job.p, report.data(), report.size(), &length), "report");
        check(report.find("\"rotation_deg\": 30.0") != std::string::npos, "inputs kept");
    }

    // The same JSON as the studio's: an expansion over weeks, its figures in the report.
    {
        Job job;
        ok(tissue_job_start_json(plane.p,
                                 R"({"mode": "expansion", "request": {"volume_cm3": 40,
                                     "expand_weeks": 1, "band_samples": 0}})",
                                 &job.p),
           "expansion json");
        ok(tissue_job_wait(job.p, -1.0), "expansion wait");
        tissue_plan_result r{};
        check(tissue_job_result(job.p, &r) != TISSUE_OK, "an expansion is not a single run");
        size_t length = 0;
        check(tissue_job_report_json(job.p, nullptr, 0, &length) == TISSUE_BUFFER_TOO_SMALL,
              "expansion query");
        std::string report(length, '\0');
        ok(tissue_job_report_json(job.p, report.data(), report.size(), &length),
           "expansion report");
        check(report.find("\"mode\": \"expansion\"") != std::string::npos, "expansion mode");
        check(report.find("\"flap_area_cm2\"") != std::string::npos, "the flap at removal");
    }

    std::printf("%d failures\n", failures);
    return failures == 0 ? 0 : 1;
}
