//! The HTTP shell (axum). Handlers extract, check limits, run the work on
//! a bounded blocking pool, map errors and serialise. Only the health
//! check exists so far; the routes of issue #6 build on [`AppState`].

use std::sync::Arc;

use axum::routing::get;
use axum::Router;

use crate::template::format::Template;

pub mod problem;
pub mod store;

/// Shared state of the service.
#[derive(Debug, Clone, Default)]
pub struct AppState {
    /// The template library (the built-in templates, validated at start).
    pub templates: Arc<Vec<Template>>,
}

impl AppState {
    /// State with the built-in template library loaded and checked
    /// against its schema; the error names the template that failed.
    pub fn with_builtin_templates() -> Result<Self, String> {
        let templates = crate::template::library::builtin().map_err(|(name, e)| format!("template `{name}`: {e}"))?;
        Ok(Self { templates: Arc::new(templates) })
    }
}

/// The service's router.
pub fn app(state: AppState) -> Router {
    Router::new().route("/healthz", get(|| async { "ok" })).with_state(state)
}

#[cfg(test)]
mod tests {
    use super::*;
    use axum::body::Body;
    use axum::http::{Request, StatusCode};
    use tower::ServiceExt;

    #[tokio::test]
    async fn healthz_answers_ok() {
        let state = AppState::with_builtin_templates().unwrap();
        assert_eq!(state.templates.len(), 3);
        let resp = app(state).oneshot(Request::get("/healthz").body(Body::empty()).unwrap()).await.unwrap();
        assert_eq!(resp.status(), StatusCode::OK);
    }
}
