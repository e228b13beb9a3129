//! `--robot sim|nav2`: which robot a run drives. The dry run and preview always use the
//! simulator; only execution goes to Nav2.

use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::sync::Arc;

use clap::{Args, ValueEnum};
use map_core::{IvlMap, Robot, SimRobot};
use robot_ros2::{FrameConfig, Nav2Options, Nav2Robot, RosDistro};

use crate::error::CliError;

/// Which robot executes plans.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub(crate) enum RobotKind {
    /// The built-in simulator on the map.
    #[default]
    Sim,
    /// A real (or simulated) robot running ROS 2 Nav2, over DDS.
    Nav2,
}

/// The robot flags.
#[derive(Debug, Clone, Args)]
pub(crate) struct RobotArgs {
    /// Which robot executes the plan.
    #[arg(long, value_enum, default_value_t = RobotKind::Sim)]
    pub(crate) robot: RobotKind,
    /// DDS domain of the robot (nav2).
    #[arg(long, env = "ROS_DOMAIN_ID", default_value_t = 0)]
    pub(crate) ros_domain_id: u16,
    /// The robot's ROS 2 distro: humble, jazzy or kilted (nav2; Nav2's message layouts differ).
    #[arg(long, default_value = "jazzy", value_parser = parse_distro)]
    pub(crate) ros_distro: RosDistro,
    /// JSON file tying the IVLMap frame to the robot's `map` frame (nav2; identity when absent).
    #[arg(long)]
    pub(crate) frame_config: Option<PathBuf>,
    /// Seconds to wait for Nav2's action server and a first pose (nav2).
    #[arg(long, default_value_t = 10.0)]
    pub(crate) ros_wait_s: f64,
}

fn parse_distro(s: &str) -> Result<RosDistro, String> {
    s.parse()
}

impl RobotKind {
    /// Its name on the command line (and in `ivlmap serve`'s API).
    pub(crate) fn name(self) -> &'static str {
        match self {
            RobotKind::Sim => "sim",
            RobotKind::Nav2 => "nav2",
        }
    }
}

/// Open the robot for a run on `map`: a simulator at the map's start pose, or Nav2 at
/// the robot's pose. Ctrl-C cancels Nav2's active goal (the run then fails, keeping
/// what was driven).
pub(crate) fn open_robot(args: &RobotArgs, map: &Arc<IvlMap>) -> Result<Box<dyn Robot>, CliError> {
    match open_real(args, map)? {
        Some(real) => Ok(real),
        None => Ok(Box::new(SimRobot::new(map.clone()))),
    }
}

/// The real robot of `args` (connected, Ctrl-C wired to cancel its goal), or `None`
/// for the simulator.
pub(crate) fn open_real(
    args: &RobotArgs,
    map: &Arc<IvlMap>,
) -> Result<Option<Box<dyn Robot + Send>>, CliError> {
    match args.robot {
        RobotKind::Sim => Ok(None),
        RobotKind::Nav2 => {
            let frames = match &args.frame_config {
                Some(p) => FrameConfig::load(p).map_err(|e| CliError::Input(e.to_string()))?,
                None => FrameConfig::default(),
            };
            if !(args.ros_wait_s.is_finite() && args.ros_wait_s > 0.0 && args.ros_wait_s < 3600.0) {
                return Err(CliError::Input(format!(
                    "--ros-wait-s {} must be in 0..3600",
                    args.ros_wait_s
                )));
            }
            let wait = std::time::Duration::from_secs_f64(args.ros_wait_s);
            let opts = Nav2Options {
                domain_id: args.ros_domain_id,
                distro: args.ros_distro,
                frames,
                server_timeout: wait,
                pose_timeout: wait,
                ..Nav2Options::default()
            };
            let robot = Nav2Robot::connect(opts, Some(map.clone()))
                .map_err(|e| CliError::Failed(format!("connecting to the robot: {e}")))?;
            let flag = robot.cancel_flag();
            // Ctrl-C: cancel the goal; a second one ends the process.
            let hit = Arc::new(std::sync::atomic::AtomicBool::new(false));
            std::thread::spawn(move || {
                let Ok(rt) = tokio::runtime::Builder::new_current_thread()
                    .enable_io()
                    .build()
                else {
                    return;
                };
                rt.block_on(async {
                    while tokio::signal::ctrl_c().await.is_ok() {
                        if hit.swap(true, Ordering::SeqCst) {
                            std::process::exit(130);
                        }
                        eprintln!("Ctrl-C: canceling the robot's goal (again to quit)");
                        flag.store(true, Ordering::SeqCst);
                    }
                });
            });
            Ok(Some(Box::new(robot)))
        }
    }
}
