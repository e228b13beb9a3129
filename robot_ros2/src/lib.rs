//! A ROS 2 Nav2 driver behind `map_core`'s [`map_core::Robot`] trait, on the pure-Rust
//! `ros2-client` (RustDDS): no ROS install is needed to build or run it.
//!
//! - `msgs`: the ROS message types it speaks (serde, CDR), Nav2's `NavigateToPose`
//!   per distro ([`RosDistro`]);
//! - `frames`: the IVLMap frame and the robot's `map` frame ([`FrameConfig`]),
//!   compass headings and ROS yaw;
//! - `tf`: the robot's pose from `/tf` (`map -> odom -> base_link`) or `/amcl_pose`;
//! - `nav2`: [`Nav2Robot`], every robot call as a `navigate_to_pose` goal;
//! - `error`: [`Ros2Error`].

pub mod error;
pub mod frames;
pub mod msgs;
pub mod nav2;
pub mod tf;
mod wait;

pub use crate::error::Ros2Error;
pub use crate::frames::FrameConfig;
pub use crate::msgs::RosDistro;
pub use crate::nav2::{Nav2Options, Nav2Robot};
