"""An rclpy stand-in for Nav2: hosts navigate_to_pose (nav2_msgs/action/NavigateToPose)
and publishes /tf (map -> odom -> base_link). The base turns toward the goal, drives
straight to it, then turns to the goal's yaw. Used by robot_ros2/tests/cross_stack.rs.
usage: python nav2_node.py X Y YAW   (start pose in map; runs until killed)"""
import math
import sys
import time

import rclpy
from rclpy.action import ActionServer, CancelResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from geometry_msgs.msg import TransformStamped
from nav2_msgs.action import NavigateToPose
from tf2_msgs.msg import TFMessage

SPEED, TURN, DT = 3.0, 6.0, 0.02


def wrap(a):
    return math.atan2(math.sin(a), math.cos(a))


def yaw_of(q):
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


class Nav2StandIn(Node):
    def __init__(self, start):
        super().__init__("nav2_rclpy_standin")
        self.pose = list(start)
        group = ReentrantCallbackGroup()
        self.tf = self.create_publisher(TFMessage, "/tf", 10)
        self.create_timer(DT, self.publish_tf, callback_group=group)
        ActionServer(self, NavigateToPose, "navigate_to_pose", self.execute,
                     cancel_callback=lambda _g: CancelResponse.ACCEPT, callback_group=group)

    def publish_tf(self):
        t = TransformStamped()
        t.header.stamp = self.get_clock().now().to_msg()
        t.header.frame_id, t.child_frame_id = "map", "odom"
        t.transform.rotation.w = 1.0
        b = TransformStamped()
        b.header.stamp = t.header.stamp
        b.header.frame_id, b.child_frame_id = "odom", "base_link"
        b.transform.translation.x, b.transform.translation.y = self.pose[0], self.pose[1]
        b.transform.rotation.z = math.sin(self.pose[2] / 2)
        b.transform.rotation.w = math.cos(self.pose[2] / 2)
        self.tf.publish(TFMessage(transforms=[t, b]))

    def step_toward(self, gx, gy, gyaw):
        dx, dy = gx - self.pose[0], gy - self.pose[1]
        dist = math.hypot(dx, dy)
        turn = lambda to: self.pose[2] + max(-TURN * DT, min(TURN * DT, wrap(to - self.pose[2])))
        if dist > 1e-3:
            bearing = math.atan2(dy, dx)
            back = abs(wrap(bearing - gyaw)) > 2.0 and abs(wrap(self.pose[2] - gyaw)) < 1e-3
            face = wrap(bearing + math.pi) if back else bearing
            if abs(wrap(face - self.pose[2])) > 1e-3:
                self.pose[2] = wrap(turn(face))
            else:
                s = min(SPEED * DT, dist)
                self.pose[0] += s * dx / dist
                self.pose[1] += s * dy / dist
            return dist, False
        if abs(wrap(gyaw - self.pose[2])) > 1e-3:
            self.pose[2] = wrap(turn(gyaw))
            return 0.0, False
        return 0.0, True

    def execute(self, handle):
        p = handle.request.pose.pose
        goal = (p.position.x, p.position.y, yaw_of(p.orientation))
        while True:
            if handle.is_cancel_requested:
                handle.canceled()
                return NavigateToPose.Result()
            dist, done = self.step_toward(*goal)
            fb = NavigateToPose.Feedback()
            fb.current_pose.header.frame_id = "map"
            fb.current_pose.pose.position.x, fb.current_pose.pose.position.y = self.pose[0], self.pose[1]
            fb.current_pose.pose.orientation.z = math.sin(self.pose[2] / 2)
            fb.current_pose.pose.orientation.w = math.cos(self.pose[2] / 2)
            fb.distance_remaining = float(dist)
            handle.publish_feedback(fb)
            if done:
                self.publish_tf()
                handle.succeed()
                return NavigateToPose.Result()
            time.sleep(DT)


def main():
    rclpy.init()
    node = Nav2StandIn([float(v) for v in sys.argv[1:4]])
    ex = MultiThreadedExecutor(num_threads=4)
    ex.add_node(node)
    print("ready", flush=True)
    ex.spin()


if __name__ == "__main__":
    main()
