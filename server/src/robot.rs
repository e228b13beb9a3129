//! The one real robot of `ivlmap serve --robot nav2`, shared by every session.
//!
//! A physical robot cannot be in two places: one session drives it at a time. A session
//! takes the robot with its first instruction that moves it, and keeps it until it is
//! deleted or expires (idle for the session lifetime); meanwhile other sessions still
//! plan and preview (on the simulator, from the robot's pose), and are refused with
//! 409 `robot_busy` when they ask the robot to move. Undo cannot drive a real robot
//! back: it forgets the last instruction from the conversation, and the robot stays.

use std::sync::{Mutex, MutexGuard};

use map_core::{Pose, Robot};

/// Another session drives the robot.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "another session drives the {kind} robot; it is free again when that session is \
     deleted or has been idle for the session lifetime (previews work meanwhile)"
)]
pub struct RobotBusy {
    /// The robot's kind (`nav2`).
    pub kind: String,
}

/// A real robot shared by all sessions, driven by one at a time.
pub struct SharedRobot {
    kind: String,
    robot: Mutex<Box<dyn Robot + Send>>,
    /// The pose last read, for readers while a run holds the robot.
    last_pose: Mutex<Pose>,
    driver: Mutex<Option<String>>,
}

impl std::fmt::Debug for SharedRobot {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SharedRobot")
            .field("kind", &self.kind)
            .field("driver", &self.driver())
            .finish_non_exhaustive()
    }
}

fn unpoisoned<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // Nothing here panics while holding a lock; the data stays whole if something did.
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

impl SharedRobot {
    /// `robot` (connected) under the name `kind` (`nav2`).
    #[must_use]
    pub fn new(kind: impl Into<String>, robot: Box<dyn Robot + Send>) -> Self {
        let pose = robot.pose();
        Self {
            kind: kind.into(),
            robot: Mutex::new(robot),
            last_pose: Mutex::new(pose),
            driver: Mutex::new(None),
        }
    }

    /// Its kind, e.g. `nav2`.
    #[must_use]
    pub fn kind(&self) -> &str {
        &self.kind
    }

    /// The robot's pose read now, or the last one read while a run holds the robot.
    #[must_use]
    pub fn pose(&self) -> Pose {
        match self.robot.try_lock() {
            Ok(mut r) => {
                let p = r.current_pose();
                *unpoisoned(&self.last_pose) = p;
                p
            }
            Err(_) => *unpoisoned(&self.last_pose),
        }
    }

    /// The session that drives it, if any.
    #[must_use]
    pub fn driver(&self) -> Option<String> {
        unpoisoned(&self.driver).clone()
    }

    /// Takes the robot for session `id`: free, already `id`'s, or held by a session
    /// that `alive` says is gone.
    ///
    /// # Errors
    /// [`RobotBusy`] when another live session drives it.
    pub fn claim(&self, id: &str, alive: impl Fn(&str) -> bool) -> Result<(), RobotBusy> {
        let mut d = unpoisoned(&self.driver);
        match d.as_deref() {
            Some(holder) if holder != id && alive(holder) => Err(RobotBusy {
                kind: self.kind.clone(),
            }),
            _ => {
                *d = Some(id.to_string());
                Ok(())
            }
        }
    }

    /// Whether session `id` could take it now (see [`SharedRobot::claim`]).
    #[must_use]
    pub fn free_for(&self, id: &str, alive: impl Fn(&str) -> bool) -> bool {
        unpoisoned(&self.driver)
            .as_deref()
            .is_none_or(|holder| holder == id || !alive(holder))
    }

    /// Lets go of the robot if session `id` holds it.
    pub fn release(&self, id: &str) {
        let mut d = unpoisoned(&self.driver);
        if d.as_deref() == Some(id) {
            *d = None;
        }
    }

    /// Runs `f` on the robot (blocking: call it off the async runtime), then notes its
    /// pose.
    pub fn with<T>(&self, f: impl FnOnce(&mut dyn Robot) -> T) -> T {
        let mut r = unpoisoned(&self.robot);
        let out = f(r.as_mut());
        *unpoisoned(&self.last_pose) = r.pose();
        out
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use map_core::{IvlMap, Scene, SimRobot};
    use std::sync::Arc;

    #[test]
    fn one_live_session_drives_at_a_time() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../examples/scenes/flat-a.scene.json"
        );
        let map = Arc::new(IvlMap::from_scene(&Scene::from_path(path).unwrap()));
        let r = SharedRobot::new("sim", Box::new(SimRobot::new(map.clone())));
        let live = |_: &str| true;
        assert!(r.claim("a", live).is_ok() && r.claim("a", live).is_ok());
        assert!(r.claim("b", live).is_err() && !r.free_for("b", live));
        assert!(r.claim("b", |s| s != "a").is_ok(), "a is gone: b takes it");
        r.release("a");
        assert_eq!(r.driver().as_deref(), Some("b"));
        r.release("b");
        assert!(r.driver().is_none() && r.free_for("a", live));
        assert_eq!(r.pose(), map.start_pose);
    }
}
