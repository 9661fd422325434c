"""Type stubs for curvestereo (the extension is python/src/*.cpp)."""

from os import PathLike
from collections.abc import Iterator
from typing import Any, Callable, Literal, Protocol
from typing import Sequence as _Sequence

import numpy as np
import numpy.typing as npt

__version__: str

_Path = str | PathLike[str]
# Host images: 2-D uint8 / uint16 / float32 (gray) or H x W x 3|4 (R G B [A]), any strides.
_HostImage = npt.NDArray[np.uint8] | npt.NDArray[np.uint16] | npt.NDArray[np.float32]

class _CudaArray(Protocol):
    """CuPy / PyTorch / Numba arrays (CUDA builds only)."""

    @property
    def __cuda_array_interface__(self) -> dict[str, Any]: ...

class _DLPackArray(Protocol):
    def __dlpack__(self, *, stream: int | None = ...) -> Any: ...
    def __dlpack_device__(self) -> tuple[int, int]: ...

_Image = _HostImage | _CudaArray | _DLPackArray
_F32 = npt.NDArray[np.float32]
# Stereo.next's pose, T_world_cam0 (X_world = R X_cam0 + t): a 4 x 4 array (last row
# 0 0 0 1), or an (R, t) pair (3 x 3, 3 values). R must be a rotation.
_Pose = npt.ArrayLike | tuple[npt.ArrayLike, npt.ArrayLike]

class Error(RuntimeError):
    """Every failure of the library: a one-line message naming the file or value."""

class Rig:
    """A calibrated stereo rig: two cameras and the pose of camera 1 (X1 = R X0 + t)."""

    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def R(self) -> npt.NDArray[np.float64]:
        """3 x 3 rotation of camera 1 relative to camera 0."""
    @property
    def t(self) -> npt.NDArray[np.float64]:
        """Translation of camera 1 relative to camera 0, metres (3,)."""
    @property
    def baseline(self) -> float: ...
    @property
    def cam0(self) -> dict[str, Any]:
        """{'model', 'width', 'height', 'params': [fx, fy, cx, cy, ...]}."""
    @property
    def cam1(self) -> dict[str, Any]: ...
    def scaled(self, factor: float) -> Rig:
        """The rig for images rescaled by `factor` (0.5: a half-resolution stream)."""
    def save(
        self, path: _Path, format: Literal["kalibr", "basalt", "opencv", "orbslam3", "vins"] = "kalibr"
    ) -> None:
        """Write the rig in a calibration format (OpenCV: XML when path ends in .xml)."""

class DeviceArray:
    """A result on the GPU (compute(..., return_device=True)); CuPy and PyTorch wrap it
    without copying (cupy.asarray, cupy.from_dlpack, torch.from_dlpack, torch.as_tensor).
    It owns its memory; wrappers keep it alive. CUDA builds only."""

    @property
    def __cuda_array_interface__(self) -> dict[str, Any]: ...
    def __dlpack__(
        self, *, stream: int | None = None, max_version: Any = None, dl_device: Any = None, copy: Any = None
    ) -> Any: ...
    def __dlpack_device__(self) -> tuple[int, int]: ...
    @property
    def shape(self) -> tuple[int, ...]: ...
    @property
    def dtype(self) -> np.dtype[Any]: ...
    @property
    def ptr(self) -> int: ...
    @property
    def device_id(self) -> int: ...
    def get(self) -> npt.NDArray[Any]:
        """A NumPy copy on the host."""

class Result:
    """One frame's output (NumPy arrays, or DeviceArray with return_device=True).
    Invalid pixels are NaN in every float output."""

    @property
    def depth(self) -> _F32 | DeviceArray:
        """Radial depth (distance from camera 0's centre), metres, H x W; NaN invalid, +inf at infinity."""
    @property
    def z(self) -> _F32 | DeviceArray | None:
        """Depth along camera 0's optical axis (None without the 'points' output)."""
    @property
    def points(self) -> _F32 | DeviceArray | None:
        """Camera-0 points, metres, H x W x 3 (NaN where invalid or infinite)."""
    @property
    def disparity(self) -> _F32 | DeviceArray | None:
        """Disparity along the epipolar curve, px, H x W."""
    @property
    def warp(self) -> _F32 | DeviceArray | None:
        """2-D displacement into the calibrated right image, px, H x W x 2."""
    @property
    def valid(self) -> npt.NDArray[np.bool_] | DeviceArray:
        """Pixels that were solved."""
    @property
    def confidence(self) -> _F32 | DeviceArray | None:
        """How far each pixel can be trusted, [0, 1] (NaN where not valid); None only if left out."""
    @property
    def stages(self) -> dict[str, float]:
        """Milliseconds per stage ({} when profiling is off)."""
    @property
    def total_ms(self) -> float: ...
    @property
    def warm(self) -> bool:
        """next(): the frame started from the previous frame's estimate (False from compute())."""
    @property
    def redone(self) -> bool:
        """next(): a warm frame failed its check (warm_fail_ratio) and was solved again cold."""
    @property
    def consistent_share(self) -> float:
        """next(): share of the valid pixels at the sweep's level that passed its left-right
        check; NaN from compute(), without the initialiser and on the GPU-array path."""
    @property
    def mean_confidence(self) -> float:
        """next(): mean confidence over the field of view, which falls where the images
        disagree with the estimate; NaN from compute(), with warm_fail_ratio 0 and on the
        GPU-array path."""
    @property
    def lr_pass_share(self) -> float:
        """lr_check: share of the field of view whose left-right round trip passed; NaN
        without lr_check and on the GPU-array path."""

class Stereo:
    """The solver for one rig: set up once, then compute() per frame. Not for two threads
    at once (raises Error if used so); use one per thread."""

    def __init__(
        self,
        rig: Rig,
        preset: str = "realtime",
        backend: str = "auto",
        *,
        device: int | str = ...,
        outputs: _Sequence[Literal["disparity", "warp", "points", "depth", "valid", "z"]] | None = None,
        profile: bool | None = None,
        # Solver parameters (Stereo.params lists them all; CLI spellings such as
        # max_fov, median, init_parallax and dashes are accepted too).
        levels: int = ...,
        scale: float = ...,
        min_width: int = ...,
        warps: int = ...,
        warps_taper: int = ...,
        iterations: int = ...,
        du_max: float = ...,
        median_filter: bool = ...,
        edge_upsample: bool = ...,
        data_term: Literal["normalised", "brightness"] = ...,
        norm_sigma: float = ...,
        noise_level: float = ...,
        lambda_: float = ...,
        alpha0: float = ...,
        alpha1: float = ...,
        beta: float = ...,
        eta: float = ...,
        w_min: float = ...,
        tensor_sigma: float = ...,
        gamma: float = ...,
        init: Literal["none", "planesweep"] = ...,
        init_level: int = ...,
        init_max_parallax_deg: float = ...,
        init_px_per_plane: float = ...,
        init_radius: int = ...,
        init_p1: float = ...,
        init_p2: float = ...,
        lr_tolerance_px: float = ...,
        init_accept: float = ...,
        init_max_cost: float = ...,
        occlusion_weight: float = ...,
        init_warps: int = ...,
        init_band: int = ...,
        max_fov_deg: float = ...,
        epipole_deg: float = ...,
        # Sequences (next()): warm start, cold schedule, warm-failure check, temporal filter.
        warm_start: bool = ...,
        warm_band: int = ...,
        warm_coarse_warps: int = ...,
        warm_full_res_warps: int = ...,
        cold_every: int = ...,
        warm_fail_ratio: float = ...,
        temporal_strength: float = ...,
        temporal_gate: float = ...,
        # Confidence and validity (docs/confidence.md): plain regions filled with the plane
        # their border agrees on, the other direction's round trip, points at infinity, pixels
        # the image cannot fix, a confidence floor.
        plain_fill: bool = ...,
        plain_fill_level: int = ...,
        lr_check: bool = ...,
        lr_check_px: float = ...,
        infinity_px: float = ...,
        infinity_bound_px: float = ...,
        max_deviation_px: float = ...,
        reject_below: float = ...,
        **more: Any,
    ) -> None: ...
    def compute(
        self,
        left: _Image,
        right: _Image,
        *,
        progress: Callable[[float], object] | None = None,
        return_device: bool = False,
    ) -> Result:
        """Solve one pair (the GIL is released meanwhile). GPU arrays need the CUDA backend."""
    def next(
        self,
        left: _Image,
        right: _Image,
        pose: _Pose | None = None,
        *,
        progress: Callable[[float], object] | None = None,
        return_device: bool = False,
    ) -> Result:
        """The next frame of a sequence: warm-started from the previous frame (moved by the
        change of pose when both have one), filtered over time; Result.warm tells. Raises
        Error on a pose of another shape or a non-rotation."""
    def reset_sequence(self) -> None:
        """A new sequence: the next next() is solved cold, nothing carried into it."""
    def set_pose(self, R: npt.ArrayLike, t: npt.ArrayLike) -> None:
        """A moving camera: the second view's pose relative to the first (X1 = R X0 + t)."""
    def set_mask(self, mask: npt.ArrayLike) -> None:
        """Solve only where mask != 0 (H x W)."""
    @property
    def backend(self) -> str: ...
    @property
    def device(self) -> str: ...
    @property
    def backend_choice(self) -> str: ...
    @property
    def buffer_bytes(self) -> int: ...
    @property
    def rig(self) -> Rig: ...
    @property
    def params(self) -> dict[str, Any]: ...
    @property
    def outputs(self) -> list[str]: ...

class CameraRig:
    """A rig of N >= 2 cameras, each with its pose in one body frame (load_rig)."""

    def __len__(self) -> int: ...
    @property
    def cameras(self) -> list[dict[str, Any]]:
        """Each camera as {'model', 'width', 'height', 'params'} (as Rig.cam0)."""
    @property
    def poses(self) -> list[npt.NDArray[np.float64]]:
        """Each camera's 4 x 4 T_body_cam."""
    @property
    def centre(self) -> npt.NDArray[np.float64]:
        """The mean of the camera centres, body frame (3,)."""
    def pairs(self, partners: int = 2) -> list[dict[str, Any]]:
        """The pairs RigStereo solves by default: {'i', 'j', 'overlap_ij', 'overlap_ji', 'baseline'}."""
    def overlaps(self) -> list[dict[str, Any]]:
        """Every pair i < j with its overlaps and baseline (as `calib show` prints them)."""
    def pair(self, i: int, j: int) -> Rig:
        """The stereo Rig of cameras i (cam0) and j (cam1)."""

class Panorama:
    """Equirectangular, W x W/2: longitude -180..180 left to right, +90 latitude at the top."""

    @property
    def range(self) -> _F32:
        """Metres from the centre; +inf at infinity, NaN where no camera gave a depth."""
    @property
    def grey(self) -> _F32: ...
    @property
    def confidence(self) -> _F32: ...
    @property
    def width(self) -> int: ...
    @property
    def centre(self) -> npt.NDArray[np.float64]: ...

class RigResult:
    """One frame of a rig: a Result per camera, and the panorama on request."""

    @property
    def cameras(self) -> list[Result]: ...
    @property
    def solves(self) -> list[dict[str, Any]]:
        """{'reference', 'other', 'window', 'ms', 'cross_check_invalidated', 'warm', 'redone'} per pair
        direction; window: (x0, y0, width, height), the part of the reference's image solved."""
    @property
    def total_ms(self) -> float: ...
    def panorama(
        self, width: int = 2048, centre: npt.ArrayLike | None = None, min_confidence: float = 0.0
    ) -> Panorama:
        """The cameras' depths fused around the rig, as `curvestereo run --calib rig.yaml` does,
        on the RigStereo's backend."""

class RigStereo:
    """The solver for a rig of N cameras: every pair both ways, fused per camera. Not for two
    threads at once (raises Error if used so)."""

    def __init__(
        self,
        rig: CameraRig,
        preset: str = "realtime",
        backend: str = "auto",
        *,
        pairs: str | _Sequence[tuple[int, int]] | None = None,
        partners: int = 2,
        cross_check: float = 0.0,
        device: int | str = ...,
        **params: Any,
    ) -> None: ...
    def compute(self, images: _Sequence[_HostImage]) -> RigResult:
        """One image per camera, in order, each at its camera's size."""
    def next(self, images: _Sequence[_HostImage], pose: _Pose | None = None) -> RigResult:
        """A frame of a sequence: every pair direction continues its own sequence as
        Stereo.next does. pose: the rig's T_world_body, or None."""
    def reset_sequence(self) -> None:
        """The next frame starts a new sequence (cold)."""
    @property
    def rig(self) -> CameraRig: ...
    @property
    def pairs(self) -> list[dict[str, Any]]: ...
    @property
    def params(self) -> dict[str, Any]: ...
    @property
    def cross_check(self) -> float: ...
    @property
    def backend(self) -> str: ...

class RigFrame:
    """One frame of a RigSequence: one image per camera, read on first use, then kept."""

    @property
    def index(self) -> int: ...
    @property
    def timestamp_ns(self) -> int:
        """Camera 0's timestamp."""
    @property
    def images(self) -> list[_F32]:
        """One float32 H x W image in [0, 1] per camera, in order."""
    @property
    def pose(self) -> npt.NDArray[np.float64] | None:
        """The rig's T_world_body, 4 x 4 (what RigStereo.next takes), or None."""
    @property
    def paths(self) -> list[str]: ...

class RigSequence:
    """A rig's recording: an ASL / EuRoC folder with one cam<k> per camera.

        rig = curvestereo.load_rig("rec/camchain.yaml")
        stereo = curvestereo.RigStereo(rig)
        for f in curvestereo.RigSequence("rec", rig):
            r = stereo.next(f.images, pose=f.pose)
    """

    def __init__(
        self,
        source: _Path,
        rig: CameraRig,
        poses: _Path | None = None,
        pair_tolerance_ms: float = 1.0,
        pose_tolerance_ms: float = 5.0,
    ) -> None:
        """source: the folder holding mav0/ (or mav0/ itself) with cam0 ... cam<N-1>. poses:
        camera 0's (T_world_cam0; default the folder's poses_cam0.csv)."""
    def __len__(self) -> int: ...
    def __getitem__(self, index: int) -> RigFrame: ...
    def __iter__(self) -> Iterator[RigFrame]: ...
    @property
    def warnings(self) -> list[str]:
        """Images in no frame, frames without a pose: one line each."""
    @property
    def summary(self) -> str: ...

class Frame:
    """One stereo frame of a Sequence; left / right are read on first use, then kept."""

    @property
    def index(self) -> int: ...
    @property
    def timestamp_ns(self) -> int:
        """Camera 0's timestamp."""
    @property
    def left(self) -> _F32:
        """Camera 0's image, float32 H x W in [0, 1] (as read_image)."""
    @property
    def right(self) -> _F32: ...
    @property
    def pose(self) -> npt.NDArray[np.float64] | None:
        """T_world_cam0, 4 x 4 (what Stereo.next takes), or None."""
    @property
    def left_path(self) -> str: ...
    @property
    def right_path(self) -> str: ...

class _ReadAhead:
    """Sequence.read_ahead()'s iterator: frames read on background threads, in order."""

    def __iter__(self) -> _ReadAhead: ...
    def __next__(self) -> Frame: ...
    @property
    def threads(self) -> int: ...
    @property
    def first_wait_ms(self) -> float: ...
    @property
    def waited_ms(self) -> float: ...
    @property
    def read_ms(self) -> float: ...

class Sequence:
    """A recorded stereo sequence, images read one frame at a time.

        seq = curvestereo.Sequence("seq/")               # an ASL / EuRoC folder
        stereo = curvestereo.Stereo(curvestereo.load_calibration("seq/camchain.yaml"))
        for f in seq:
            r = stereo.next(f.left, f.right, pose=f.pose)
    """

    def __init__(
        self,
        source: _Path | tuple[_Path, _Path],
        poses: _Path | None = None,
        pair_tolerance_ms: float = 1.0,
        pose_tolerance_ms: float = 5.0,
    ) -> None:
        """source: an ASL / EuRoC folder (holding mav0/, or mav0/ itself), or two image
        folders / globs as "LEFT,RIGHT" or (left, right). poses: EuRoC CSV or TUM text of
        T_world_cam0 (default: the ASL folder's poses_cam0.csv)."""
    def __len__(self) -> int: ...
    def __getitem__(self, index: int) -> Frame: ...
    def __iter__(self) -> Iterator[Frame]: ...
    def read_ahead(self, threads: int = 0) -> _ReadAhead: ...
    @property
    def warnings(self) -> list[str]:
        """Unpaired frames, frames without a pose, mismatched names: one line each."""
    @property
    def summary(self) -> str: ...
    @property
    def timestamps_ns(self) -> npt.NDArray[np.int64]: ...
    @property
    def source(self) -> str: ...
    @staticmethod
    def from_log(
        path: _Path,
        topics: tuple[str, str],
        poses: _Path | None = None,
        pair_tolerance_ms: float = 1.0,
        pose_tolerance_ms: float = 5.0,
    ) -> Sequence:
        """A recorded log's stereo frames (MCAP, ROS 1 bag 2.0, rosbag2 .db3 or bag folder):
        two sensor_msgs/Image or CompressedImage topics paired by header.stamp. A log cut
        short is read up to the cut; .warnings says where."""

class DepthLogWriter:
    """Depth into an MCAP log (profile ros2, CDR, ros2msg schemas): PREFIX/depth (32FC1
    radial), PREFIX/camera_info, PREFIX/points (organised PointCloud2), PREFIX/confidence,
    and with pinhole PREFIX/depth_pinhole (REP-118 z-depth) and its camera_info.

        with curvestereo.DepthLogWriter("depth.mcap", rig) as out:
            out.write(frame.timestamp_ns, stereo.next(frame.left, frame.right))
    """

    def __init__(
        self,
        path: _Path,
        rig: Rig,
        compression: Literal["zstd", "lz4", "none"] = "zstd",
        min_confidence: float = 0.0,
        pinhole: float | tuple[float, int, int] | None = None,
        topic_prefix: str = "/curvestereo",
        frame_id: str = "cam0",
    ) -> None: ...
    def write(self, timestamp_ns: int, result: Result) -> None: ...
    def close(self) -> None: ...
    @property
    def frames(self) -> int: ...
    def __enter__(self) -> DepthLogWriter: ...
    def __exit__(self, *exc: object) -> None: ...

def log_info(path: _Path) -> dict[str, Any]:
    """A log's format, topics (name, type, serialisation, messages, first_ns, last_ns),
    messages, start_ns, end_ns and cut ('' unless the log was cut short)."""

def load_calibration(path: _Path) -> Rig:
    """Read a stereo calibration: Kalibr / OpenVINS camchain, Basalt calibration.json, OpenCV
    FileStorage YAML / XML, ORB-SLAM3 settings or VINS-Fusion config (the format told from
    the keys; docs/calibration.md)."""

def load_rig(path: _Path) -> CameraRig:
    """Read an N-camera calibration (Kalibr camchain cam0..camN-1, or Basalt), validated."""

def read_image(path: _Path) -> _F32:
    """PNG (8/16-bit; colour -> Rec. 601 luma) scaled to [0, 1], EXR, or .flo (H x W x 2)."""

def write_png(path: _Path, image: npt.ArrayLike, bits: Literal[8, 16] = 8) -> None:
    """H x W float32 in [0, 1] / uint8 / uint16 (gray) or H x W x 3 uint8 (RGB)."""

def write_exr(path: _Path, image: _F32) -> None: ...
def write_ply(path: _Path, points: npt.ArrayLike, colours: npt.ArrayLike | None = None) -> None:
    """The finite points of an (..., 3) array; colours gray (...) or RGB (..., 3)."""

def depth_picture(depth: npt.ArrayLike) -> npt.NDArray[np.uint8]:
    """H x W x 3 uint8, as `curvestereo run`'s depth.png."""

def colorize(values: npt.ArrayLike, lo: float, hi: float) -> npt.NDArray[np.uint8]: ...
def presets() -> list[str]: ...
def preset_params(name: str) -> dict[str, Any]: ...
def available_backends(usable: bool = False) -> list[str]: ...
def build_info() -> dict[str, Any]: ...
