#!/usr/bin/python3
"""Open3D's ICP (point-to-plane by default) for the registration benchmarks:
the moving cloud registered on the reference, the 4 x 4 matrix written to
MATRIX_OUT. Normals of the reference from 30 neighbours within 1 m (Open3D's
hybrid search), as its tutorial does.
--local: both clouds shifted by the reference's centroid first (and the matrix
shifted back), as an Open3D user must do with georeferenced data: in UTM
coordinates its ICP diverges.
Usage: open3d-icp.py MOVING REFERENCE MATRIX_OUT [--max-distance D] [--point-to-point] [--local]"""
import sys

import numpy as np
import open3d as o3d

moving = o3d.io.read_point_cloud(sys.argv[1])
reference = o3d.io.read_point_cloud(sys.argv[2])
max_distance = float(sys.argv[sys.argv.index("--max-distance") + 1]) if "--max-distance" in sys.argv else 10.0
shift = np.zeros(3)
if "--local" in sys.argv:
    shift = np.asarray(reference.points).mean(axis=0)
    moving.translate(-shift)
    reference.translate(-shift)
if "--point-to-point" in sys.argv:
    estimation = o3d.pipelines.registration.TransformationEstimationPointToPoint()
else:
    reference.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=1.0, max_nn=30))
    estimation = o3d.pipelines.registration.TransformationEstimationPointToPlane()
result = o3d.pipelines.registration.registration_icp(
    moving, reference, max_distance, np.eye(4), estimation,
    o3d.pipelines.registration.ICPConvergenceCriteria(max_iteration=100))
to_local = np.eye(4)
to_local[:3, 3] = -shift
np.savetxt(sys.argv[3], np.linalg.inv(to_local) @ result.transformation @ to_local, fmt="%.17g")
print(f"fitness {result.fitness:.4f}, inlier RMSE {result.inlier_rmse:.6f}")
