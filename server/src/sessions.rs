//! Sessions: each has its own simulated robot, its chat history (agent's [`Session`]),
//! an undo stack, a previewed plan waiting for confirmation, and an event channel the
//! page listens on. The store is bounded (a session limit, idle expiry) and every
//! change to a session happens under its turn lock, one instruction at a time.

use std::collections::{HashMap, VecDeque};
use std::hash::{BuildHasher, Hasher};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use agent::{PlannedInstruction, Session};
use map_core::{IvlMap, SimRobot};
use serde_json::Value;
use tokio::sync::broadcast;

/// Events kept for a slow listener before it starts missing some.
const EVENT_BUFFER: usize = 1024;

/// One server-sent event: its name and JSON data.
#[derive(Debug, Clone, PartialEq)]
pub struct ServerEvent {
    /// `queued`, `planning`, `tuples`, `script`, `step`, `done`.
    pub name: &'static str,
    /// The event's JSON.
    pub data: Value,
}

/// What a session holds.
#[derive(Debug, Clone)]
pub struct SessionState {
    /// The robot (pose and whole trajectory).
    pub robot: SimRobot,
    /// The conversation.
    pub chat: Session,
    /// Earlier (robot, conversation) pairs, most recent last.
    pub undo: VecDeque<(SimRobot, Session)>,
    /// A previewed plan waiting for confirm or cancel.
    pub pending: Option<Box<PlannedInstruction>>,
}

impl SessionState {
    /// A fresh robot at the map's start pose and an empty conversation.
    #[must_use]
    pub fn fresh(map: &Arc<IvlMap>) -> Self {
        Self::fresh_at(map, map.start_pose)
    }

    /// A fresh robot at `pose` (a real robot's) and an empty conversation.
    #[must_use]
    pub fn fresh_at(map: &Arc<IvlMap>, pose: map_core::Pose) -> Self {
        use map_core::Robot as _;
        let robot = SimRobot::with_pose(map.clone(), pose);
        let chat = Session::new(robot.pose());
        Self {
            robot,
            chat,
            undo: VecDeque::new(),
            pending: None,
        }
    }
}

/// A live session.
#[derive(Debug)]
pub struct SessionEntry {
    /// Its id.
    pub id: String,
    /// Held while an instruction (or undo, reset, confirm) changes the session, so
    /// changes happen one at a time and a failed one changes nothing.
    pub turn: tokio::sync::Mutex<()>,
    state: Mutex<SessionState>,
    events: broadcast::Sender<ServerEvent>,
    last_used: Mutex<Instant>,
    requests: AtomicU64,
}

impl SessionEntry {
    fn new(id: String, state: SessionState) -> Self {
        let (events, _) = broadcast::channel(EVENT_BUFFER);
        Self {
            id,
            turn: tokio::sync::Mutex::new(()),
            state: Mutex::new(state),
            events,
            last_used: Mutex::new(Instant::now()),
            requests: AtomicU64::new(0),
        }
    }

    /// The state, for a short look or a commit (never held across an await).
    pub fn state(&self) -> MutexGuard<'_, SessionState> {
        // Nothing panics while holding it; if something did, the data is still whole
        // (commits are single assignments).
        self.state
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// Marks the session used now.
    pub fn touch(&self) {
        *self
            .last_used
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner) = Instant::now();
    }

    fn idle(&self) -> Duration {
        self.last_used
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .elapsed()
    }

    /// The next request number (1, 2, ...); events carry it as `request`.
    pub fn next_request(&self) -> u64 {
        self.requests.fetch_add(1, Ordering::Relaxed) + 1
    }

    /// Sends an event to whoever listens (nobody is fine).
    pub fn emit(&self, name: &'static str, request: u64, mut data: Value) {
        if let Value::Object(m) = &mut data {
            m.insert("request".into(), Value::from(request));
        }
        let _ = self.events.send(ServerEvent { name, data });
    }

    /// A sender for events from another thread.
    #[must_use]
    pub fn events(&self) -> broadcast::Sender<ServerEvent> {
        self.events.clone()
    }

    /// A new listener.
    #[must_use]
    pub fn subscribe(&self) -> broadcast::Receiver<ServerEvent> {
        self.events.subscribe()
    }
}

/// The session store is full.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("{max} sessions are open, the most this server keeps; delete one or try again later")]
pub struct TooManySessions {
    /// The limit.
    pub max: usize,
}

/// Every live session.
#[derive(Debug)]
pub struct SessionStore {
    map: Arc<IvlMap>,
    sessions: Mutex<HashMap<String, Arc<SessionEntry>>>,
    max: usize,
    ttl: Duration,
    created: AtomicU64,
}

impl SessionStore {
    /// A store of at most `max` sessions that drops those idle for `ttl`.
    #[must_use]
    pub fn new(map: Arc<IvlMap>, max: usize, ttl: Duration) -> Self {
        Self {
            map,
            sessions: Mutex::new(HashMap::new()),
            max,
            ttl,
            created: AtomicU64::new(0),
        }
    }

    fn lock(&self) -> MutexGuard<'_, HashMap<String, Arc<SessionEntry>>> {
        self.sessions
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// A new session with the robot at the map's start pose.
    ///
    /// # Errors
    /// [`TooManySessions`] when the store is full even after dropping idle ones.
    pub fn create(&self) -> Result<Arc<SessionEntry>, TooManySessions> {
        if self.len() >= self.max {
            self.expire();
        }
        let n = self.created.fetch_add(1, Ordering::Relaxed);
        let entry = Arc::new(SessionEntry::new(new_id(n), SessionState::fresh(&self.map)));
        let mut all = self.lock();
        if all.len() >= self.max {
            return Err(TooManySessions { max: self.max });
        }
        all.insert(entry.id.clone(), entry.clone());
        Ok(entry)
    }

    /// The session `id`, marked used.
    #[must_use]
    pub fn get(&self, id: &str) -> Option<Arc<SessionEntry>> {
        let e = self.lock().get(id).cloned();
        if let Some(e) = &e {
            e.touch();
        }
        e
    }

    /// Whether session `id` is open (without marking it used).
    #[must_use]
    pub fn contains(&self, id: &str) -> bool {
        self.lock().contains_key(id)
    }

    /// Removes `id`; whether it was there.
    pub fn remove(&self, id: &str) -> bool {
        self.lock().remove(id).is_some()
    }

    /// Sessions open.
    #[must_use]
    pub fn len(&self) -> usize {
        self.lock().len()
    }

    /// Whether none is open.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Drops sessions idle longer than the lifetime (not one with an instruction in
    /// flight); returns how many went.
    pub fn expire(&self) -> usize {
        let mut all = self.lock();
        let before = all.len();
        all.retain(|_, e| e.idle() < self.ttl || e.turn.try_lock().is_err());
        before - all.len()
    }

    /// The lifetime of an idle session.
    #[must_use]
    pub fn ttl(&self) -> Duration {
        self.ttl
    }
}

/// A 128-bit session id in hex. SipHash keyed by the process's random hasher keys, over
/// a counter and the clock: unpredictable to clients, unique within the process (the
/// token, not the id, is what guards a server off loopback).
fn new_id(n: u64) -> String {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or_default();
    let half = |salt: u64| {
        let mut h = std::collections::hash_map::RandomState::new().build_hasher();
        h.write_u64(n);
        h.write_u64(salt);
        h.write_u128(nanos);
        h.finish()
    };
    format!("{:016x}{:016x}", half(0x5e55_1011), half(n ^ 0x1d))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use map_core::Scene;

    fn store(max: usize, ttl: Duration) -> SessionStore {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../examples/scenes/flat-a.scene.json"
        );
        let map = Arc::new(IvlMap::from_scene(&Scene::from_path(path).unwrap()));
        SessionStore::new(map, max, ttl)
    }

    #[test]
    fn bounded_and_idle_sessions_expire() {
        let s = store(2, Duration::from_millis(100));
        let a = s.create().unwrap();
        let b = s.create().unwrap();
        assert_ne!(a.id, b.id);
        assert_eq!(a.id.len(), 32);
        assert!(s.create().is_err(), "full");
        std::thread::sleep(Duration::from_millis(150));
        let busy = b.turn.try_lock().unwrap();
        assert_eq!(s.expire(), 1, "the busy one stays");
        assert!(s.get(&a.id).is_none() && s.get(&b.id).is_some());
        drop(busy);
        assert!(s.create().is_ok());
        assert!(s.remove(&b.id) && !s.remove(&b.id));
    }
}
