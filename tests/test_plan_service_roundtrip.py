"""A real PlanPath server and client in one process, over Fast DDS."""

import math

from builtin_interfaces.msg import Duration
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rpr3_gwr_msgs.msg import GlobalPath, PlatformPose
from rpr3_gwr_msgs.srv import PlanPath
from trajectory_msgs.msg import JointTrajectoryPoint


def _answer(request, response):
    """Echo the request back in a response with non-trivial contents."""
    response.success = True
    response.error_code = PlanPath.Response.ERROR_NONE
    response.feasibility = PlanPath.Response.FEASIBILITY_CONNECTED
    response.global_paths = [GlobalPath(patch_ids=[64, 42, 24, 12], cost=31.5),
                             GlobalPath(patch_ids=[64, 56, 24, 12], cost=29.25)]
    response.path_index = 1
    response.trajectory.joint_names = ["rho1", "rho2", "rho3"]
    for k in range(3):
        point = JointTrajectoryPoint()
        rho1, rho2, rho3 = request.start.positions
        point.positions = [rho1, rho2 + k, rho3 - k]
        point.velocities = [0.0, 0.5 * k, -0.5 * k]
        point.time_from_start = Duration(sec=k, nanosec=250_000_000)
        response.trajectory.points.append(point)
    response.poses = [PlatformPose(names=["x", "y", "alpha"],
                                   values=[1.0 * k, -2.0 * k, request.goal.mode])
                      for k in range(3)]
    response.min_singularity_margin = 0.0267
    return response


def test_plan_request_and_response_cross_dds_intact(ros_context):
    server = Node("plan_server", context=ros_context)
    client_node = Node("plan_client", context=ros_context)
    executor = SingleThreadedExecutor(context=ros_context)
    try:
        server.create_service(PlanPath, "plan_path", _answer)
        client = client_node.create_client(PlanPath, "plan_path")
        executor.add_node(server)
        executor.add_node(client_node)
        assert client.wait_for_service(timeout_sec=10.0)
        request = PlanPath.Request()
        request.start.joint_names = ["rho1", "rho2", "rho3"]
        request.start.positions = [17.0, 12.0, 18.0]
        request.start.mode = math.radians(122.82)
        request.goal.positions = [17.0, 10.0, 25.0]
        request.goal.mode = math.radians(-24.24)
        request.max_velocity, request.max_acceleration = 2.0, 4.0
        future = client.call_async(request)
        executor.spin_until_future_complete(future, timeout_sec=10.0)
        assert future.done(), "no response within 10 s"
        response = future.result()
        assert response.success and response.error_code == PlanPath.Response.ERROR_NONE
        assert [list(g.patch_ids) for g in response.global_paths] == [[64, 42, 24, 12],
                                                                       [64, 56, 24, 12]]
        assert response.global_paths[1].cost == 29.25 and response.path_index == 1
        assert list(response.trajectory.joint_names) == ["rho1", "rho2", "rho3"]
        assert [list(p.positions) for p in response.trajectory.points] == [
            [17.0, 12.0, 18.0], [17.0, 13.0, 17.0], [17.0, 14.0, 16.0]]
        assert response.trajectory.points[2].time_from_start == Duration(sec=2,
                                                                         nanosec=250_000_000)
        assert [p.values[2] for p in response.poses] == [request.goal.mode] * 3
        assert list(response.poses[2].names) == ["x", "y", "alpha"]
        assert response.poses[2].values[1] == -4.0 and response.min_singularity_margin == 0.0267
    finally:
        executor.shutdown()
        server.destroy_node()
        client_node.destroy_node()
