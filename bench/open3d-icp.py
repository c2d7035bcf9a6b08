#!/usr/bin/python3
"""Open3D's ICP (point-to-plane by default) for the registration benchmarks:
the moving cloud registered on the reference, the 4 x 4 matrix written to
MATRIX_OUT. Normals of the reference from 30 neighbours within 1 m (Open3D's
hybrid search), as its tutorial does.
--local: both clouds shifted by the reference's centroid first (and the matrix
shifted back), as an Open3D user must do with georeferenced data: in UTM
coordinates its ICP diverges.
--global: first Open3D's global registration pipeline (its tutorial's: voxel
0.7 m like scandiff's automatic spacing here, FPFH within 5 voxels, RANSAC
with mutual matches and its edge-length and distance checkers, 100 000
iterations), then the ICP from there within 3 voxels.
Usage: open3d-icp.py MOVING REFERENCE MATRIX_OUT [--max-distance D] [--point-to-point] [--local] [--global]"""
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
initial = np.eye(4)
if "--global" in sys.argv:
    voxel = 0.7
    reg = o3d.pipelines.registration

    def prepared(cloud):
        down = cloud.voxel_down_sample(voxel)
        down.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=2 * voxel, max_nn=30))
        return down, reg.compute_fpfh_feature(down, o3d.geometry.KDTreeSearchParamHybrid(radius=5 * voxel, max_nn=100))

    (moving_down, moving_fpfh), (reference_down, reference_fpfh) = prepared(moving), prepared(reference)
    coarse = reg.registration_ransac_based_on_feature_matching(
        moving_down, reference_down, moving_fpfh, reference_fpfh, True, 1.5 * voxel,
        reg.TransformationEstimationPointToPoint(False), 3,
        [reg.CorrespondenceCheckerBasedOnEdgeLength(0.9), reg.CorrespondenceCheckerBasedOnDistance(1.5 * voxel)],
        reg.RANSACConvergenceCriteria(100000, 0.999))
    initial = coarse.transformation
    max_distance = 3 * voxel
if "--point-to-point" in sys.argv:
    estimation = o3d.pipelines.registration.TransformationEstimationPointToPoint()
else:
    reference.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=1.0, max_nn=30))
    estimation = o3d.pipelines.registration.TransformationEstimationPointToPlane()
result = o3d.pipelines.registration.registration_icp(
    moving, reference, max_distance, initial, estimation,
    o3d.pipelines.registration.ICPConvergenceCriteria(max_iteration=100))
to_local = np.eye(4)
to_local[:3, 3] = -shift
np.savetxt(sys.argv[3], np.linalg.inv(to_local) @ result.transformation @ to_local, fmt="%.17g")
print(f"fitness {result.fitness:.4f}, inlier RMSE {result.inlier_rmse:.6f}")
