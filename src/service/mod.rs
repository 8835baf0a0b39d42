//! The HTTP shell (axum). Handlers extract, check limits, run the work on
//! a bounded blocking pool, map errors and serialise.

use axum::routing::get;
use axum::Router;

/// Shared state of the service.
#[derive(Debug, Clone, Default)]
pub struct AppState {}

/// The service's router.
pub fn app(state: AppState) -> Router {
    Router::new().route("/healthz", get(|| async { "ok" })).with_state(state)
}
