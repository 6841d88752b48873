"""FlowFusion: dynamic dense RGB-D SLAM (robust dense odometry, optical-flow segmentation of moving
objects, a surfel map of the static scene). NumPy arrays in and out; the C++ engine does the work.

    seq = flowfusion.TumSequence('demo_sequence')
    system = flowfusion.System(seq.camera, flowfusion.Config(), T_world_first=seq.initial_pose())
    for frame in seq:
        r = system.process(frame)      # the form that matches `flowfusion run`
    system.save('out', sequence=seq)

The engine is the extension flowfusion._flowfusion, whose names this package exports;
flowfusion.batch runs many sequences (and a grid of settings) as Dask tasks
(`python3 -m flowfusion.batch --help`).
"""
from ._flowfusion import *  # noqa: F401,F403 (the engine's classes and functions are the package's API)
from ._flowfusion import __version__  # noqa: F401
