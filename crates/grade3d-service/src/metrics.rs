//! Prometheus metrics (the `prometheus` crate, text exposition format 0.0.4
//! at `/metrics`): requests by route, method and status; latency histograms
//! by route; time per pipeline stage; work queue depth; cache hits and
//! misses (results and per-body obstacles); jobs by state.

use prometheus::{
    Encoder, HistogramOpts, HistogramVec, IntCounterVec, IntGauge, IntGaugeVec, Opts, Registry, TextEncoder,
};

/// The service's metrics.
#[derive(Debug, Clone)]
pub struct Metrics {
    registry: Registry,
    /// Requests answered, by route, method and status.
    pub requests: IntCounterVec,
    /// Request latency, seconds, by route.
    pub latency: HistogramVec,
    /// Pipeline stage time, seconds, by stage.
    pub stages: HistogramVec,
    /// Work items admitted to the pool and not finished.
    pub queue_depth: IntGauge,
    /// Cache lookups by cache and outcome (`hit`/`miss`).
    pub cache: IntCounterVec,
    /// Jobs by state.
    pub jobs: IntGaugeVec,
}

const LATENCY_BUCKETS: &[f64] = &[0.001, 0.005, 0.01, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0, 30.0, 60.0, 120.0];

impl Metrics {
    /// Registers every metric in a fresh registry.
    ///
    /// # Panics
    /// Never on input: only if the metric definitions below were invalid
    /// (a programming error caught by the unit test).
    pub fn new() -> Self {
        let registry = Registry::new_custom(Some("grade3d".into()), None).expect("static prefix is valid");
        let requests = IntCounterVec::new(
            Opts::new("http_requests_total", "HTTP requests answered"),
            &["route", "method", "status"],
        )
        .expect("static metric");
        let latency = HistogramVec::new(
            HistogramOpts::new("http_request_duration_seconds", "HTTP request latency")
                .buckets(LATENCY_BUCKETS.to_vec()),
            &["route"],
        )
        .expect("static metric");
        let stages = HistogramVec::new(
            HistogramOpts::new("stage_duration_seconds", "Time per pipeline stage per request")
                .buckets(LATENCY_BUCKETS.to_vec()),
            &["stage"],
        )
        .expect("static metric");
        let queue_depth =
            IntGauge::new("queue_depth", "Work items admitted to the pool and not finished").expect("static");
        let cache = IntCounterVec::new(Opts::new("cache_lookups_total", "Cache lookups"), &["cache", "outcome"])
            .expect("static metric");
        let jobs = IntGaugeVec::new(Opts::new("jobs", "Batch jobs by state"), &["state"]).expect("static metric");
        for c in [
            Box::new(requests.clone()) as Box<dyn prometheus::core::Collector>,
            Box::new(latency.clone()),
            Box::new(stages.clone()),
            Box::new(queue_depth.clone()),
            Box::new(cache.clone()),
            Box::new(jobs.clone()),
        ] {
            registry.register(c).expect("metric names are unique");
        }
        Self { registry, requests, latency, stages, queue_depth, cache, jobs }
    }

    /// The text exposition of every metric.
    pub fn render(&self) -> String {
        let mut buf = Vec::new();
        if let Err(e) = TextEncoder::new().encode(&self.registry.gather(), &mut buf) {
            tracing::error!(error = %e, "metrics encoding failed");
        }
        String::from_utf8(buf).unwrap_or_default()
    }

    /// Records a flow's stage timings (ms).
    pub fn observe_stages(&self, timings: &std::collections::BTreeMap<String, f64>) {
        for (stage, ms) in timings {
            self.stages.with_label_values(&[stage.as_str()]).observe(ms / 1e3);
        }
    }
}

impl Default for Metrics {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_metric_is_exposed() {
        let m = Metrics::new();
        m.requests.with_label_values(&["/healthz", "GET", "200"]).inc();
        m.latency.with_label_values(&["/healthz"]).observe(0.002);
        m.stages.with_label_values(&["refine"]).observe(0.05);
        m.cache.with_label_values(&["results", "hit"]).inc();
        m.jobs.with_label_values(&["done"]).set(1);
        m.queue_depth.set(3);
        let text = m.render();
        for name in [
            "grade3d_http_requests_total",
            "grade3d_http_request_duration_seconds_bucket",
            "grade3d_stage_duration_seconds_sum",
            "grade3d_queue_depth 3",
            "grade3d_cache_lookups_total",
            "grade3d_jobs",
        ] {
            assert!(text.contains(name), "{name} missing from\n{text}");
        }
    }
}
