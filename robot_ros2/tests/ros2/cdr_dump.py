"""Prints rclpy's CDR (hex) of the fixed messages robot_ros2/tests/cross_stack.rs
encodes with ros2-client, one `name hex` per line."""
from rclpy.serialization import serialize_message
from geometry_msgs.msg import PoseStamped
from nav2_msgs.action import NavigateToPose

ps = PoseStamped()
ps.header.stamp.sec, ps.header.stamp.nanosec = 1700000000, 123456789
ps.header.frame_id = "map"
ps.pose.position.x, ps.pose.position.y, ps.pose.position.z = 1.5, -2.25, 0.0
ps.pose.orientation.z, ps.pose.orientation.w = 0.6, 0.8
print("pose_stamped", serialize_message(ps).hex())

req = NavigateToPose.Impl.SendGoalService.Request()
req.goal_id.uuid = list(range(1, 17))
req.goal.pose = ps
req.goal.behavior_tree = "bt.xml"
print("send_goal_request", serialize_message(req).hex())

res = NavigateToPose.Result()
res.error_code, res.error_msg = 9002, "no transform"
print("result", serialize_message(res).hex())
