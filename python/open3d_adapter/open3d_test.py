"""The one helper Open3D's test file imports from its test folder: the devices to run on
(volley's scene runs on the CPU)."""
import open3d as o3d


def list_devices(**_):
    return [o3d.core.Device("CPU:0")]
