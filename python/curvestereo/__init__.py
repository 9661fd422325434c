"""curvestereo: dense depth from a calibrated fisheye stereo pair, over the whole field of
view, without rectifying or undistorting the images.

    import curvestereo as cs
    rig = cs.load_calibration("camchain.yaml")
    stereo = cs.Stereo(rig, preset="realtime")
    r = stereo.compute(cs.read_image("left.png"), cs.read_image("right.png"))
    r.depth   # float32 H x W, radial metres, NaN where invalid

A recording, frame after frame (warm start and temporal filter; poses optional):

    seq = cs.Sequence("seq/")                 # an ASL / EuRoC folder, or ("left/", "right/")
    stereo = cs.Stereo(cs.load_calibration("seq/camchain.yaml"))
    for f in seq:                             # Frame: images read when first used
        r = stereo.next(f.left, f.right, pose=f.pose)   # pose: 4 x 4 T_world_cam0 or None
        print(f.timestamp_ns, r.warm, r.consistent_share)

A rig of N cameras (a Kalibr camchain or Basalt calibration with N cameras): each
camera's depth from its pairs, and the panorama around the rig:

    rig = cs.load_rig("camchain.yaml")        # rig.overlaps(): as `calib show` prints
    stereo = cs.RigStereo(rig)                # pairs: rig.pairs(), or pairs="0-1,1-2"
    r = stereo.compute([cs.read_image(f"cam{k}.png") for k in range(len(rig))])
    r.cameras[0].depth                        # a Result per camera
    p = r.panorama(width=2048)                # p.range, p.grey, p.confidence: W/2 x W

Every failure raises curvestereo.Error (a RuntimeError) with the library's one-line
message. See help(curvestereo.Stereo) and docs/guide.md, "Python".
"""

# NumPy first: the extension needs it at run time, and this names what is missing.
import numpy as _numpy  # noqa: F401

try:
    from . import _curvestereo  # noqa: F401
except ImportError as e:  # e.g. python/curvestereo itself on sys.path, not the build's copy
    raise ImportError(
        f"curvestereo's compiled module is missing beside {__file__}: build it (docs/guide.md 'Python': "
        "cmake ... then PYTHONPATH=build/python) or pip install the project"
    ) from e

from ._curvestereo import (  # noqa: F401
    CameraRig,
    DepthLogWriter,
    Error,
    Frame,
    Panorama,
    Result,
    Rig,
    RigFrame,
    RigResult,
    RigSequence,
    RigStereo,
    Sequence,
    Stereo,
    __version__,
    available_backends,
    build_info,
    colorize,
    depth_picture,
    load_calibration,
    load_rig,
    log_info,
    preset_params,
    presets,
    read_image,
    write_exr,
    write_ply,
    write_png,
)

__all__ = [
    "CameraRig",
    "DepthLogWriter",
    "Error",
    "Frame",
    "Panorama",
    "Result",
    "Rig",
    "RigFrame",
    "RigResult",
    "RigSequence",
    "RigStereo",
    "Sequence",
    "Stereo",
    "available_backends",
    "build_info",
    "colorize",
    "depth_picture",
    "load_calibration",
    "load_rig",
    "log_info",
    "preset_params",
    "presets",
    "read_image",
    "write_exr",
    "write_ply",
    "write_png",
]

try:  # only in builds with the CUDA backend
    from ._curvestereo import DeviceArray  # noqa: F401

    __all__.append("DeviceArray")
except ImportError:
    pass

# Report the public module in reprs and tracebacks, not the extension's private name.
for _name in __all__:
    _obj = globals()[_name]
    if isinstance(_obj, type):
        _obj.__module__ = __name__
del _name, _obj
