//! The routes of formats.md's "HTTP API", plus additive ones: `GET /api/info` (scene,
//! backend, model, queue), `POST /api/sessions/{id}/confirm` and `/cancel` (run or drop
//! the previewed plan), `POST /api/sessions/{id}/reset` (robot back to the start, history
//! cleared), and the page's own files.
//!
//! With a real robot (`--robot nav2`), additively: `robot` in `/api/info` and in a
//! session, 409 `robot_busy` when another session drives it, and `note` in undo's
//! answer (the robot is not driven back).

use std::convert::Infallible;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use agent::{LanguageError, Outcome, PlannedInstruction, Session};
use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::{DefaultBodyLimit, Path, Request, State};
use axum::http::{header, HeaderMap, StatusCode};
use axum::middleware::{self, Next};
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use futures_util::stream::{self, Stream, StreamExt};
use map_core::render::{render_trajectory_rgb, RenderOptions};
use map_core::{Pose, Robot as _, SimRobot, Trajectory};
use serde::Deserialize;
use serde_json::{json, Value};
use tokio::sync::{broadcast, oneshot};

use crate::app::AppState;
use crate::error::ApiError;
use crate::reply::{steps, stretch, InstructionReply, Kind};
use crate::sessions::{SessionEntry, SessionState};

type St = State<Arc<AppState>>;

/// The router: the page, and `/api` behind the token check and the body limit.
pub(crate) fn router(state: Arc<AppState>) -> Router {
    let limit = state.config.body_limit;
    let api = Router::new()
        .route("/api/info", get(info))
        .route("/api/map", get(map))
        .route("/api/sessions", post(create_session))
        .route(
            "/api/sessions/{id}",
            get(get_session).delete(delete_session),
        )
        .route("/api/sessions/{id}/instructions", post(instruction))
        .route("/api/sessions/{id}/confirm", post(confirm))
        .route("/api/sessions/{id}/cancel", post(cancel))
        .route("/api/sessions/{id}/undo", post(undo))
        .route("/api/sessions/{id}/reset", post(reset))
        .route("/api/sessions/{id}/events", get(events))
        .route("/api/sessions/{id}/map.png", get(map_png))
        .route_layer(middleware::from_fn_with_state(state.clone(), auth));
    Router::new()
        .route("/", get(page))
        .route("/index.html", get(page))
        .route("/assets/app.js", get(app_js))
        .route("/assets/app.css", get(app_css))
        .merge(api)
        .fallback(not_found)
        .method_not_allowed_fallback(method_not_allowed)
        .layer(DefaultBodyLimit::max(limit))
        .with_state(state)
}

// ---------------------------------------------------------------------------- page

async fn page() -> Html<&'static str> {
    Html(crate::page::INDEX_HTML)
}

async fn app_js() -> Response {
    (
        [(header::CONTENT_TYPE, "text/javascript; charset=utf-8")],
        crate::page::APP_JS,
    )
        .into_response()
}

async fn app_css() -> Response {
    (
        [(header::CONTENT_TYPE, "text/css; charset=utf-8")],
        crate::page::APP_CSS,
    )
        .into_response()
}

async fn not_found() -> ApiError {
    ApiError::new(
        StatusCode::NOT_FOUND,
        "not_found",
        "no such route (see formats.md, \"HTTP API\")",
    )
}

async fn method_not_allowed() -> ApiError {
    ApiError::new(
        StatusCode::METHOD_NOT_ALLOWED,
        "method_not_allowed",
        "this route does not take that method (see formats.md, \"HTTP API\")",
    )
}

// ---------------------------------------------------------------------------- auth

/// Equal in constant time for equal lengths (the token's length is not secret).
fn same_secret(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

async fn auth(State(st): St, req: Request, next: Next) -> Response {
    if let Some(token) = &st.config.token {
        let given = req
            .headers()
            .get(header::AUTHORIZATION)
            .and_then(|v| v.to_str().ok())
            .and_then(|v| v.strip_prefix("Bearer "))
            .map(str::trim);
        if !given.is_some_and(|g| same_secret(g.as_bytes(), token.as_bytes())) {
            return ApiError::unauthorized().into_response();
        }
    }
    next.run(req).await
}

// ---------------------------------------------------------------------------- bodies

fn body(body: Result<Bytes, BytesRejection>, limit: usize) -> Result<Bytes, ApiError> {
    match body {
        Ok(b) => Ok(b),
        Err(r) if r.status() == StatusCode::PAYLOAD_TOO_LARGE => Err(ApiError::too_large(limit)),
        Err(r) => Err(ApiError::bad_request(format!(
            "cannot read the request body: {}",
            r.body_text()
        ))),
    }
}

/// A JSON object into `T` (serde would also take an array for a struct: not here).
fn parse<T: serde::de::DeserializeOwned>(bytes: &[u8]) -> Result<T, ApiError> {
    let v: Value = serde_json::from_slice(bytes)
        .map_err(|e| ApiError::bad_request(format!("malformed JSON: {e}")))?;
    if !v.is_object() {
        return Err(ApiError::bad_request(
            "the body must be a JSON object, e.g. {\"text\": \"go to the red sofa\"}",
        ));
    }
    serde_json::from_value(v)
        .map_err(|e| ApiError::bad_request(format!("the JSON has a wrong or missing field: {e}")))
}

#[derive(Debug, Deserialize)]
struct InstructionBody {
    text: String,
    #[serde(default)]
    preview: bool,
}

// ---------------------------------------------------------------------------- info, map

async fn info(State(st): St) -> Json<Value> {
    let svc = &st.service;
    Json(json!({
        "scene": svc.map.name,
        "backend": svc.backend.name(),
        "model": svc.backend.model(),
        // Worked examples per request: "all" (in the cached prefix) or the K most similar.
        "examples": svc.options.examples.map_or_else(|| "all".to_string(), |k| k.to_string()),
        "prompts": svc.prompts.label(),
        "queue": st.queue.stats(),
        "sessions": st.sessions.len(),
        "limits": {
            "body_bytes": st.config.body_limit,
            "max_sessions": st.config.max_sessions,
            "max_queue": st.config.max_queue,
            "session_ttl_s": st.config.session_ttl.as_secs(),
            "request_timeout_s": st.config.request_timeout.as_secs(),
            "undo_depth": st.config.undo_depth,
            "max_turns": st.config.max_turns,
            "max_instruction_chars": st.config.max_instruction_chars,
        },
        "version": env!("CARGO_PKG_VERSION"),
        "robot": match &svc.robot {
            None => json!({"kind": "sim", "shared": false}),
            Some(r) => json!({"kind": r.kind(), "shared": true, "driven": r.driver().is_some()}),
        },
    }))
}

async fn map(State(st): St) -> Response {
    // Serialised per request: the map is small (tens of kB) and this keeps no copy.
    Json(&st.map_json).into_response()
}

// ---------------------------------------------------------------------------- sessions

fn session(st: &AppState, id: &str) -> Result<Arc<SessionEntry>, ApiError> {
    st.sessions
        .get(id)
        .ok_or_else(|| ApiError::unknown_session(id))
}

/// The session's `robot`: which, and with a shared one whether this session drives it
/// and whether it could.
fn robot_json(st: &AppState, id: &str) -> Value {
    match &st.service.robot {
        None => json!({"kind": "sim", "shared": false}),
        Some(r) => json!({
            "kind": r.kind(),
            "shared": true,
            "driving": r.driver().as_deref() == Some(id),
            "free": r.free_for(id, |s| st.sessions.contains(s)),
        }),
    }
}

fn busy(e: &crate::robot::RobotBusy) -> ApiError {
    ApiError::new(StatusCode::CONFLICT, "robot_busy", e.to_string())
}

/// 409 `robot_busy` unless session `id` may drive `real` now.
fn refuse_unless_free(
    st: &AppState,
    real: &crate::robot::SharedRobot,
    id: &str,
) -> Result<(), ApiError> {
    if real.free_for(id, |s| st.sessions.contains(s)) {
        Ok(())
    } else {
        Err(busy(&crate::robot::RobotBusy {
            kind: real.kind().to_string(),
        }))
    }
}

/// The session's record `sim` put at `pose` (the real robot's), its trajectory kept.
fn at_pose(sim: &SimRobot, pose: Pose, add: Option<&Trajectory>) -> SimRobot {
    let mut t = sim.trajectory().clone();
    if let Some(part) = add {
        t.stops.extend(part.stops.iter().cloned());
        let pts: Vec<map_core::Point> = part
            .path
            .iter()
            .map(|p| map_core::Point::new(p[0], p[1]))
            .collect();
        t.extend_path(&pts);
        t.length_m += part.length_m;
        t.script.clone_from(&part.script);
        t.error.clone_from(&part.error);
    }
    t.final_pose = pose.to_array();
    let mut s = sim.clone();
    s.reset_to(pose);
    *s.trajectory_mut() = t;
    s
}

fn session_json(st: &AppState, e: &SessionEntry) -> Value {
    let robot = robot_json(st, &e.id);
    let s = e.state();
    json!({
        "robot": robot,
        "id": e.id,
        "scene": st.service.map.name,
        "pose": s.robot.pose().to_array(),
        "trajectory": s.robot.trajectory(),
        "turns": s.chat.turns(),
        "undo": s.undo.len(),
        "pending": s.pending.as_ref().map(|p| json!({
            "instruction": p.instruction,
            "tuples": p.tuples,
            "script": p.script,
        })),
    })
}

async fn create_session(
    State(st): St,
    raw: Result<Bytes, BytesRejection>,
) -> Result<(StatusCode, Json<Value>), ApiError> {
    let raw = body(raw, st.config.body_limit)?;
    if !raw.iter().all(u8::is_ascii_whitespace) {
        let _: serde_json::Map<String, Value> = parse(&raw)?;
    }
    let e = st.sessions.create().map_err(|e| {
        ApiError::new(
            StatusCode::SERVICE_UNAVAILABLE,
            "too_many_sessions",
            e.to_string(),
        )
    })?;
    if let Some(real) = &st.service.robot {
        *e.state() = SessionState::fresh_at(&st.service.map, real.pose());
    }
    let pose = e.state().robot.pose().to_array();
    Ok((
        StatusCode::CREATED,
        Json(json!({
            "robot": robot_json(&st, &e.id),
            "id": e.id,
            "scene": st.service.map.name,
            "pose": pose,
            "backend": st.service.backend.name(),
            "model": st.service.backend.model(),
        })),
    ))
}

async fn get_session(State(st): St, Path(id): Path<String>) -> Result<Json<Value>, ApiError> {
    let e = session(&st, &id)?;
    Ok(Json(session_json(&st, &e)))
}

async fn delete_session(State(st): St, Path(id): Path<String>) -> Result<StatusCode, ApiError> {
    if let Some(real) = &st.service.robot {
        real.release(&id);
    }
    if st.sessions.remove(&id) {
        Ok(StatusCode::NO_CONTENT)
    } else {
        Err(ApiError::unknown_session(&id))
    }
}

/// Waits for the session's turn (one change at a time), within the request timeout.
async fn turn<'a>(
    st: &AppState,
    e: &'a SessionEntry,
) -> Result<tokio::sync::MutexGuard<'a, ()>, ApiError> {
    tokio::time::timeout(st.config.request_timeout, e.turn.lock())
        .await
        .map_err(|_| {
            ApiError::model(
                "timeout",
                "the session was busy with another instruction for too long",
            )
        })
}

async fn undo(State(st): St, Path(id): Path<String>) -> Result<Json<Value>, ApiError> {
    let e = session(&st, &id)?;
    let _turn = turn(&st, &e).await?;
    {
        let mut s = e.state();
        let Some((robot, chat)) = s.undo.pop_back() else {
            return Err(ApiError::new(
                StatusCode::CONFLICT,
                "nothing_to_undo",
                "nothing to undo: no instruction has moved the robot yet",
            ));
        };
        if st.service.robot.is_none() {
            s.robot = robot;
        }
        s.chat = chat;
        s.pending = None;
    }
    let mut v = session_json(&st, &e);
    if st.service.robot.is_some() {
        v["note"] = json!(
            "the last instruction is forgotten; the real robot is not driven back and stays where it is"
        );
    }
    Ok(Json(v))
}

async fn reset(State(st): St, Path(id): Path<String>) -> Result<Json<Value>, ApiError> {
    let e = session(&st, &id)?;
    let _turn = turn(&st, &e).await?;
    *e.state() = match &st.service.robot {
        None => SessionState::fresh(&st.service.map),
        Some(real) => SessionState::fresh_at(&st.service.map, real.pose()),
    };
    Ok(Json(session_json(&st, &e)))
}

async fn cancel(State(st): St, Path(id): Path<String>) -> Result<Json<Value>, ApiError> {
    let e = session(&st, &id)?;
    let _turn = turn(&st, &e).await?;
    e.state().pending = None;
    Ok(Json(session_json(&st, &e)))
}

// ---------------------------------------------------------------------------- instructions

async fn instruction(
    State(st): St,
    Path(id): Path<String>,
    raw: Result<Bytes, BytesRejection>,
) -> Result<Json<InstructionReply>, ApiError> {
    let raw = body(raw, st.config.body_limit)?;
    let req: InstructionBody = parse(&raw)?;
    let text = req.text.trim().to_string();
    if text.is_empty() {
        return Err(ApiError::bad_request(
            "`text` is empty: say what the robot should do",
        ));
    }
    let chars = text.chars().count();
    if chars > st.config.max_instruction_chars {
        return Err(ApiError::bad_request(format!(
            "`text` is {chars} characters; at most {} are taken",
            st.config.max_instruction_chars
        )));
    }
    let e = session(&st, &id)?;
    let started = Instant::now();
    let _turn = turn(&st, &e).await?;
    let request = e.next_request();
    let result = answer(&st, &e, request, &text, req.preview, started).await;
    e.touch();
    finish(&e, request, result).map(Json)
}

async fn confirm(
    State(st): St,
    Path(id): Path<String>,
) -> Result<Json<InstructionReply>, ApiError> {
    let e = session(&st, &id)?;
    let _turn = turn(&st, &e).await?;
    if let Some(real) = &st.service.robot {
        // Refused with the previewed plan kept (a failed request changes nothing).
        refuse_unless_free(&st, real, &e.id)?;
    }
    let Some(planned) = e.state().pending.take() else {
        return Err(ApiError::new(
            StatusCode::CONFLICT,
            "nothing_to_confirm",
            "no previewed plan waits for confirmation (send an instruction with \"preview\": true first)",
        ));
    };
    let request = e.next_request();
    let result = execute(&st, &e, request, planned).await;
    finish(&e, request, result).map(Json)
}

/// Sends `done` with the reply or the error, and passes the result on.
fn finish(
    e: &SessionEntry,
    request: u64,
    result: Result<InstructionReply, ApiError>,
) -> Result<InstructionReply, ApiError> {
    match &result {
        Ok(r) => e.emit(
            "done",
            request,
            serde_json::to_value(r).unwrap_or(Value::Null),
        ),
        Err(err) => {
            let mut v = err.body();
            v["status"] = json!(err.status.as_u16());
            e.emit("done", request, v);
        }
    }
    result
}

fn language_error(err: &LanguageError) -> ApiError {
    match err {
        LanguageError::Backend(b) => ApiError::model(
            "model_unavailable",
            format!("the model could not answer: {b}"),
        ),
        LanguageError::Prompt(p) => ApiError::internal(format!("prompt template: {p}")),
        other => ApiError::model(
            "no_plan",
            format!("the model's answer could not be made into a plan: {other}"),
        ),
    }
}

/// Plans `text` on a snapshot of the session through the model queue, then previews or
/// runs it. The session changes only at the very end, and only when it all worked.
async fn answer(
    st: &AppState,
    e: &Arc<SessionEntry>,
    request: u64,
    text: &str,
    preview: bool,
    started: Instant,
) -> Result<InstructionReply, ApiError> {
    let (mut robot, chat, turns) = {
        let s = e.state();
        (s.robot.clone(), s.chat.clone(), s.chat.turns().len())
    };
    if let Some(real) = &st.service.robot {
        // Refused before the model's time is spent; taken when the plan runs.
        if !preview {
            refuse_unless_free(st, real, &e.id)?;
        }
        // Plans and previews start from where the real robot is now.
        robot = at_pose(&robot, real.pose(), None);
    }
    if !preview && turns >= st.config.max_turns {
        return Err(ApiError::new(
            StatusCode::CONFLICT,
            "session_full",
            format!(
                "this session holds {turns} instructions, the most it keeps: reset it or start a new one"
            ),
        ));
    }
    let pose = robot.pose().to_array();
    let stops = robot.trajectory().stops.len();
    let outcome = plan(st, e, request, robot.clone(), chat, text, started).await?;
    let planned = match outcome {
        Outcome::Plan(p) => p,
        Outcome::Question(q) => {
            // The next instruction may answer it.
            e.state().chat.not_done(text, &q);
            return Ok(InstructionReply::without_plan(
                text,
                Kind::Question,
                q,
                &st.service.map.name,
                pose,
                stops + 1,
            ));
        }
        Outcome::Refusal(r) => {
            e.state().chat.not_done(text, &r);
            return Ok(InstructionReply::without_plan(
                text,
                Kind::Refused,
                r,
                &st.service.map.name,
                pose,
                stops + 1,
            ));
        }
    };
    e.emit(
        "tuples",
        request,
        json!({"tuples": planned.tuples, "text": agent::tuples::tuples_paper_form(&planned.tuples)}),
    );
    e.emit("script", request, json!({"script": planned.script}));
    if !preview {
        return execute(st, e, request, planned).await;
    }
    let svc = st.service.clone();
    let (planned, dry) = tokio::task::spawn_blocking(move || {
        let dry = planner_dsl::dry_run(&planned.plan, &svc.map, &robot, &svc.limits);
        (planned, dry)
    })
    .await
    .map_err(|j| ApiError::internal(format!("the dry run failed unexpectedly: {j}")))?;
    let reply = InstructionReply::ran(&planned, dry.outcome, dry.trajectory, true, pose, stops + 1);
    e.state().pending = Some(planned);
    Ok(reply)
}

/// Sends the plan through the model queue and waits for it (within the request
/// timeout, counted from `started`). `queued` events tell the position, `planning` when
/// the model takes it up.
async fn plan(
    st: &AppState,
    e: &Arc<SessionEntry>,
    request: u64,
    robot: SimRobot,
    chat: Session,
    text: &str,
    started: Instant,
) -> Result<Outcome, ApiError> {
    let (tx, rx) = oneshot::channel::<Result<Outcome, LanguageError>>();
    let tx = Arc::new(Mutex::new(Some(tx)));
    let svc = st.service.clone();
    let text = text.to_string();
    let job_tx = tx.clone();
    let job = Box::new(move || {
        let mut ctx = agent::PlanContext::new(&svc.map).with_robot(&robot);
        ctx.options = svc.options.clone();
        let result = chat.plan(svc.backend.as_ref(), &svc.prompts, &text, &ctx);
        let sender = job_tx.lock().ok().and_then(|mut s| s.take());
        if let Some(s) = sender {
            let _ = s.send(result);
        }
    });
    let events = e.events();
    let position = Box::new(move |p: Option<usize>| {
        let (name, mut data) = match p {
            Some(k) => ("queued", json!({"position": k})),
            None => ("planning", json!({})),
        };
        data["request"] = json!(request);
        let _ = events.send(crate::sessions::ServerEvent { name, data });
    });
    let wanted = Box::new(move || {
        tx.lock()
            .ok()
            .is_some_and(|s| s.as_ref().is_some_and(|s| !s.is_closed()))
    });
    st.queue.push(job, position, wanted).map_err(|e| {
        let code = match e {
            crate::queue::QueueError::Full { .. } => "busy",
            crate::queue::QueueError::Closed => "shutting_down",
        };
        ApiError::new(StatusCode::SERVICE_UNAVAILABLE, code, e.to_string())
    })?;
    let left = st.config.request_timeout.saturating_sub(started.elapsed());
    match tokio::time::timeout(left, rx).await {
        Ok(Ok(Ok(outcome))) => Ok(outcome),
        Ok(Ok(Err(err))) => Err(language_error(&err)),
        Ok(Err(_)) => Err(ApiError::internal(
            "planning failed unexpectedly (see the server log); the session is unchanged",
        )),
        Err(_) => Err(ApiError::model(
            "timeout",
            format!(
                "no answer from the model within {} s (queue and planning); the session is unchanged",
                st.config.request_timeout.as_secs()
            ),
        )),
    }
}

/// Runs `planned` on a copy of the session's robot and conversation, then puts the
/// copies in place (the old ones go on the undo stack), and sends a `step` per library
/// call.
async fn execute(
    st: &AppState,
    e: &Arc<SessionEntry>,
    request: u64,
    planned: Box<PlannedInstruction>,
) -> Result<InstructionReply, ApiError> {
    let (robot, chat) = {
        let s = e.state();
        (s.robot.clone(), s.chat.clone())
    };
    if st.service.robot.is_some() {
        return execute_real(st, e, request, planned, robot, chat).await;
    }
    let svc = st.service.clone();
    let before = (robot.clone(), chat.clone());
    let (planned, robot, chat, run) = tokio::task::spawn_blocking(move || {
        let (mut robot, mut chat) = (robot, chat);
        let run = chat.execute(&planned, &svc.map, &mut robot, &svc.limits);
        (planned, robot, chat, run)
    })
    .await
    .map_err(|j| ApiError::internal(format!("the run failed unexpectedly: {j}")))?;
    let (old_robot, old_chat) = before;
    let tr = old_robot.trajectory();
    let part = stretch(
        robot.trajectory(),
        tr.stops.len(),
        tr.path.len(),
        tr.length_m,
    );
    let first_stop = tr.stops.len() + 1;
    let pose = robot.pose().to_array();
    commit(
        st,
        e,
        request,
        (&run, &part, first_stop),
        (old_robot, old_chat),
        robot,
        chat,
    );
    Ok(InstructionReply::ran(
        &planned, run, part, false, pose, first_stop,
    ))
}

/// Sends a run's `step` events, then puts its robot and conversation in place, the old
/// ones on the undo stack.
fn commit(
    st: &AppState,
    e: &SessionEntry,
    request: u64,
    (run, part, first_stop): (&planner_dsl::RunOutcome, &Trajectory, usize),
    old: (SimRobot, Session),
    robot: SimRobot,
    chat: Session,
) {
    for s in steps(&run.trace, part, first_stop) {
        e.emit("step", request, s);
    }
    let mut s = e.state();
    s.undo.push_back(old);
    while s.undo.len() > st.config.undo_depth {
        s.undo.pop_front();
    }
    s.robot = robot;
    s.chat = chat;
    s.pending = None;
}

/// [`execute`] on the shared real robot: taken for this session (409 `robot_busy` when
/// another drives it), the plan run on it, the stretch it drove added to the session's
/// record. The undo stack keeps the conversation (undo cannot drive the robot back).
async fn execute_real(
    st: &AppState,
    e: &Arc<SessionEntry>,
    request: u64,
    planned: Box<PlannedInstruction>,
    record: SimRobot,
    chat: Session,
) -> Result<InstructionReply, ApiError> {
    let svc = st.service.clone();
    let Some(real) = svc.robot.clone() else {
        return Err(ApiError::internal("no real robot"));
    };
    real.claim(&e.id, |s| st.sessions.contains(s))
        .map_err(|b| busy(&b))?;
    let old_chat = chat.clone();
    let (planned, chat, run, part, pose) = tokio::task::spawn_blocking(move || {
        real.with(|r| {
            r.current_pose();
            let t = r.trajectory();
            let (stops, path, length) = (t.stops.len(), t.path.len(), t.length_m);
            let mut chat = chat;
            let run = chat.execute(&planned, &svc.map, r, &svc.limits);
            let part = stretch(r.trajectory(), stops, path, length);
            (planned, chat, run, part, r.pose())
        })
    })
    .await
    .map_err(|j| ApiError::internal(format!("the run failed unexpectedly: {j}")))?;
    let first_stop = record.trajectory().stops.len() + 1;
    let updated = at_pose(&record, pose, Some(&part));
    commit(
        st,
        e,
        request,
        (&run, &part, first_stop),
        (record, old_chat),
        updated,
        chat,
    );
    Ok(InstructionReply::ran(
        &planned,
        run,
        part,
        false,
        pose.to_array(),
        first_stop,
    ))
}

// ---------------------------------------------------------------------------- events, png

async fn events(
    State(st): St,
    Path(id): Path<String>,
) -> Result<Sse<impl Stream<Item = Result<Event, Infallible>>>, ApiError> {
    let e = session(&st, &id)?;
    let rx = e.subscribe();
    let open = Event::default()
        .event("open")
        .data(json!({"session": e.id}).to_string());
    // The stream holds only the receiver: it ends when the session goes, or when the
    // server shuts down.
    drop(e);
    let closing = st.closing.subscribe();
    let rest = stream::unfold((rx, closing), |(mut rx, mut closing)| async move {
        if *closing.borrow() {
            return None;
        }
        let event = tokio::select! {
            got = rx.recv() => match got {
                Ok(ev) => Event::default().event(ev.name).data(ev.data.to_string()),
                Err(broadcast::error::RecvError::Lagged(n)) => {
                    Event::default().comment(format!("missed {n} event(s)"))
                }
                Err(broadcast::error::RecvError::Closed) => return None,
            },
            _ = closing.changed() => return None,
        };
        Some((Ok(event), (rx, closing)))
    });
    let all = stream::once(async move { Ok(open) }).chain(rest);
    Ok(Sse::new(all).keep_alive(KeepAlive::default()))
}

/// The map with `trajectory` drawn over it, as PNG bytes.
fn render(map: &map_core::IvlMap, trajectory: &Trajectory) -> Result<Vec<u8>, String> {
    let img = render_trajectory_rgb(map, trajectory, &RenderOptions::default());
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .map_err(|e| e.to_string())?;
    Ok(out.into_inner())
}

async fn map_png(State(st): St, Path(id): Path<String>) -> Result<Response, ApiError> {
    let e = session(&st, &id)?;
    let trajectory = e.state().robot.trajectory().clone();
    let svc = st.service.clone();
    let png = tokio::task::spawn_blocking(move || render(&svc.map, &trajectory))
        .await
        .map_err(|j| ApiError::internal(format!("drawing failed unexpectedly: {j}")))?
        .map_err(|m| ApiError::internal(format!("cannot encode the PNG: {m}")))?;
    let mut headers = HeaderMap::new();
    headers.insert(
        header::CONTENT_TYPE,
        header::HeaderValue::from_static("image/png"),
    );
    headers.insert(
        header::CACHE_CONTROL,
        header::HeaderValue::from_static("no-store"),
    );
    Ok((headers, png).into_response())
}
