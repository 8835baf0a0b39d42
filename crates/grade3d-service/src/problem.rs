//! RFC 9457 problem details (`application/problem+json`): every error the
//! service answers with. Client errors name what is wrong (the field or
//! element, from the typed error); 5xx bodies say nothing internal (the
//! cause goes to the log, with the request's trace span).

use axum::http::{header, HeaderValue, StatusCode};
use axum::response::{IntoResponse, Response};
use serde::{Deserialize, Serialize};

/// Media type of problem documents.
pub const PROBLEM_JSON: &str = "application/problem+json";

/// The body of [`Problem::internal`], for when a problem cannot be serialised.
const INTERNAL_BODY: &[u8] = br#"{"type":"/problems/internal","title":"Internal error","status":500,"detail":"the request could not be completed"}"#;

/// A problem document (RFC 9457 §3.1), with two extension members.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct Problem {
    /// URI reference identifying the problem type (relative: `/problems/<slug>`).
    #[serde(rename = "type")]
    pub kind: String,
    /// Short, human-readable summary of the problem type.
    pub title: String,
    /// HTTP status code.
    #[schema(minimum = 400, maximum = 599)]
    pub status: u16,
    /// Explanation of this occurrence.
    pub detail: String,
    /// The request field or element the problem concerns (extension), e.g. `body.landmarks.waist_left`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub field: Option<String>,
    /// Seconds to wait before retrying (extension; also sent as `Retry-After`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub retry_after_s: Option<u64>,
}

impl Problem {
    /// A problem of status `status`, type slug `slug`, with `detail`.
    pub fn new(status: StatusCode, slug: &str, title: &str, detail: impl Into<String>) -> Self {
        Self {
            kind: format!("/problems/{slug}"),
            title: title.to_string(),
            status: status.as_u16(),
            detail: detail.into(),
            field: None,
            retry_after_s: None,
        }
    }

    /// The same problem, naming a field.
    pub fn field(mut self, field: impl Into<String>) -> Self {
        self.field = Some(field.into());
        self
    }

    /// 400: the request is malformed or semantically invalid.
    pub fn bad_request(slug: &str, detail: impl Into<String>) -> Self {
        Self::new(StatusCode::BAD_REQUEST, slug, "Invalid request", detail)
    }

    /// 422: well-formed input the domain rejects (a body that is not a body, a
    /// template that does not fit).
    pub fn unprocessable(slug: &str, detail: impl Into<String>) -> Self {
        Self::new(StatusCode::UNPROCESSABLE_ENTITY, slug, "Unprocessable input", detail)
    }

    /// 404.
    pub fn not_found(detail: impl Into<String>) -> Self {
        Self::new(StatusCode::NOT_FOUND, "not-found", "Not found", detail)
    }

    /// 503 with `Retry-After`.
    pub fn busy(retry_after_s: u64) -> Self {
        let mut p =
            Self::new(StatusCode::SERVICE_UNAVAILABLE, "busy", "Service busy", "the work queue is full; retry later");
        p.retry_after_s = Some(retry_after_s);
        p
    }

    /// 503 when work outlived the request's time limit.
    pub fn timeout(limit: std::time::Duration, retry_after_s: u64) -> Self {
        let mut p = Self::new(
            StatusCode::SERVICE_UNAVAILABLE,
            "timeout",
            "Time limit exceeded",
            format!(
                "the work did not finish within the {} s time limit; retry later or submit a batch job",
                limit.as_secs_f64()
            ),
        );
        p.retry_after_s = Some(retry_after_s);
        p
    }

    /// 401 for a write without a valid API key.
    pub fn unauthorized(detail: impl Into<String>) -> Self {
        Self::new(StatusCode::UNAUTHORIZED, "unauthorized", "Unauthorized", detail).field("Authorization")
    }

    /// 500 that says nothing internal; log the cause where it is created.
    pub fn internal() -> Self {
        Self::new(StatusCode::INTERNAL_SERVER_ERROR, "internal", "Internal error", "the request could not be completed")
    }
}

impl IntoResponse for Problem {
    fn into_response(self) -> Response {
        let mut status = StatusCode::from_u16(self.status).unwrap_or(StatusCode::INTERNAL_SERVER_ERROR);
        let retry = self.retry_after_s;
        // a problem is plain strings and numbers; should it not serialise, a fixed 500, never an empty body
        let body = serde_json::to_vec(&self).unwrap_or_else(|e| {
            tracing::error!(error = %e, "problem document did not serialise");
            status = StatusCode::INTERNAL_SERVER_ERROR;
            INTERNAL_BODY.to_vec()
        });
        let mut resp = (status, body).into_response();
        resp.headers_mut().insert(header::CONTENT_TYPE, HeaderValue::from_static(PROBLEM_JSON));
        if let Some(s) = retry {
            if let Ok(v) = HeaderValue::from_str(&s.to_string()) {
                resp.headers_mut().insert(header::RETRY_AFTER, v);
            }
        }
        resp
    }
}
