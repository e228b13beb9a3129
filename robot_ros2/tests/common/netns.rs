//! Running a DDS test in a network namespace of its own (loopback only, so no DDS
//! packet leaves the machine), and the ROS 2 venv of `scripts/ros2-venv.sh`. Shared by
//! robot_ros2's tests and cli/tests/ros2_nav2.rs (included by path).
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::process::Command;

/// Set inside the namespace: the test body runs.
const INSIDE: &str = "IVLMAP_ROS2_NETNS";

/// The shell line that brings up loopback with multicast (DDS discovery) in a fresh
/// network namespace, then runs `"$0" "$@"`.
pub const NETNS_UP: &str = "ip link set lo up && ip link set lo multicast on && \
     ip route add 224.0.0.0/4 dev lo && exec \"$0\" \"$@\"";

/// A random ROS domain id in 1..=200.
pub fn random_domain() -> u16 {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.subsec_nanos())
        .unwrap_or(7);
    (((nanos ^ std::process::id().rotate_left(7)) % 200) + 1) as u16
}

/// Run test `name` of this test binary again inside `unshare -n` with only `lo` up and
/// a random `ROS_DOMAIN_ID`; returns `Some(domain)` when called inside (run the test
/// body), `None` outside after the inner run passed (its output is printed).
pub fn in_netns(name: &str) -> Option<u16> {
    if let Ok(d) = std::env::var(INSIDE) {
        return Some(d.parse().expect("domain id"));
    }
    let exe = std::env::current_exe().expect("test binary");
    let domain = random_domain();
    let out = Command::new("unshare")
        .args(["-n", "sh", "-c", NETNS_UP])
        .arg(&exe)
        .args([name, "--exact", "--nocapture", "--test-threads=1"])
        .env(INSIDE, domain.to_string())
        .env("ROS_DOMAIN_ID", domain.to_string())
        .output()
        .expect("unshare (util-linux) runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!("--- inside unshare -n (ROS_DOMAIN_ID {domain}) ---\n{stdout}\n{stderr}");
    assert!(
        out.status.success(),
        "{name} failed inside `unshare -n` (a network namespace with only loopback; \
         needs root or user namespaces): {}",
        out.status
    );
    assert!(
        stdout.contains("1 passed"),
        "{name} did not run inside the namespace"
    );
    None
}

/// The ROS 2 venv, built (or found cached) by scripts/ros2-venv.sh.
pub fn ros2_venv() -> std::path::PathBuf {
    let out = Command::new(ivlmap_tests::repo().join("scripts/ros2-venv.sh"))
        .stderr(std::process::Stdio::inherit())
        .output()
        .expect("scripts/ros2-venv.sh runs");
    assert!(out.status.success(), "scripts/ros2-venv.sh failed");
    std::path::PathBuf::from(String::from_utf8(out.stdout).unwrap().trim())
}

/// A `sh -c` line that sources the venv's environment, then runs `rest`.
pub fn in_venv(v: &std::path::Path, rest: &str) -> String {
    format!(". '{}/ros2-env.sh' && {rest}", v.display())
}
