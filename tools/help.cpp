#include "help.hpp"

#include "common.hpp"

#ifndef CURVESTEREO_VERSION
#define CURVESTEREO_VERSION "unknown"
#endif

namespace cs::cli {

namespace {

// What a command's help is made of: its own text, then the shared option blocks it takes.
struct CommandText {
  const char* name;
  const char* summary;  // the overview's line
  const char* text;     // usage lines and the command's own options
  bool solver;          // takes the solver options
  bool camera;          // takes the camera-model options
};

const CommandText kCommands[] = {
    {"demo", "render a synthetic fisheye pair, solve it, report accuracy",
     R"(usage: curvestereo demo [-o OUTDIR] [--size N] [--scene urban|indoor] [--seed N] [--min-confidence C]
                        [camera-model options] [solver options]

Renders a synthetic binocular fisheye pair (12 cm baseline) with exact ground truth, solves
it and prints tau>1, tau>3, the end-point error, depth abs-rel and the time per frame.

  -o, --output DIR     where the inputs, the ground truth and the outputs go (default demo_out)
  --size N             image side in pixels (default 480)
  --scene urban|indoor the procedural scene (default urban)
  --seed N             the scene's random seed (default 7)
)",
     true, true},
    {"run", "solve a calibrated pair (a rig of N cameras, or a sequence) and write depth, points and flow",
     R"(usage: curvestereo run --calib CALIB LEFT RIGHT -o OUTDIR [options] [solver options]
       curvestereo run --calib RIG IMG0 IMG1 IMG2 ... -o OUTDIR [rig options] [solver options]
       curvestereo run --sequence SRC -o OUTDIR [--calib CALIB] [--poses FILE] [--cold] [solver options]
       curvestereo run --sequence RIGDIR -o OUTDIR [--calib RIG] [--rig] [rig options] [solver options]
       curvestereo run --log FILE --topics LEFT,RIGHT --calib CALIB -o OUT.mcap|OUTDIR [--cold] [solver options]

Writes depth.exr (radial metres), depth.png, disparity.exr, flow.flo, points.ply,
points.pcd and confidence.exr/.png (docs/confidence.md) into OUTDIR.

  --calib CALIB          Kalibr / OpenVINS camchain, Basalt calibration.json, OpenCV
                         FileStorage (YAML or XML), ORB-SLAM3 settings or a VINS-Fusion config;
                         the format is told by the content (docs/calibration.md)
  --image-size WxH       the images' size, for a calibration file that holds none
  -o, --output DIR       the output folder (created)
  --scale-intrinsics     images at a uniform rescale of the calibrated resolution (e.g. half)
                         get the cameras scaled to them
  --min-confidence C     points.ply / points.pcd keep points of confidence >= C
  --pinhole FOV[,WxH]    also depth_pinhole.exr, depth_pinhole.png (mm) and camera_info.yaml:
                         z-depth in a virtual pinhole camera of FOV degrees
  --equirect W           also range_equirect.exr, W x W/2 radial range around camera 0's axis
  --sampling nearest|bilinear   how --pinhole and --equirect sample the depth (default nearest)
a rig of N cameras (three images or more, or --rig; docs/guide.md "run on a rig"):
  each camera's outputs into OUTDIR/cam<k>/, and panorama_range.exr, panorama.png,
  panorama_depth.png, panorama_confidence.exr and the merged points.ply / points.pcd into OUTDIR
  --rig                  two images are a rig of two cameras (per-camera outputs, panorama)
  --pairs I-J,...        the pairs to solve (default: each camera's best partners by overlap
                         and baseline; `calib show RIG` lists them)
  --partners N           how many partners each camera takes (default 2)
  --panorama-width W     the panorama's width, even (default 2048; its height is W/2)
  --cross-check T        each camera's depth from a pair checked against the pair's other
                         direction: pixels whose inverse ranges differ by more than T (e.g.
                         0.1) are taken away (default 0: off)
  --panorama-min-confidence C   the panorama leaves out estimates of confidence below C
                         (default 0: every estimate; fewer holes, or fewer errors)
  --whole-images         solve each pair direction on the whole reference image, not only
                         the window its partner sees (slower; the depth differs only where
                         the pyramid's levels meet the window's edge: a check)
  --one-way              solve each pair in one direction only: half the solves, a little
                         less accurate; each camera's depth beyond its own solve is its
                         partner's carried into it (no disparity or flow there)
sequences:
  --sequence SRC         an ASL/EuRoC folder (mav0/cam0, mav0/cam1; its poses_cam0.csv and
                         camchain.yaml are used) or "LEFT,RIGHT" folders or globs paired by
                         sorted name; each frame's outputs go to OUTDIR/<t_ns>/. A rig's
                         recording (an ASL folder with cam0 ... cam<N-1>, N >= 3, or --rig):
                         each frame's cameras and panorama into OUTDIR/<t_ns>/, with the rig
                         options above
  --poses FILE           camera 0's pose per frame, T_world_cam0: CSV t_ns,px,py,pz,qx,qy,qz,qw
                         or TUM text
  --pair-tolerance-ms T  left and right timestamps further apart are not paired (default 1)
  --cold                 every frame solved alone (no warm start, no temporal filter)
  --frames FIRST:END     frames FIRST to END-1 alone (either may be left out; counted from 0)
  --read-threads N       threads reading frames ahead while one is solved (default 0: one per
                         four cores, 1 to 4); the summary's "read:" line says what reading
                         cost and how long the solving thread waited for frames
recorded logs (docs/guide.md "Recorded logs"):
  --log FILE             an MCAP file, a ROS 1 bag (2.0), a rosbag2 .db3 or bag folder
  --topics LEFT,RIGHT    its two sensor_msgs/Image or CompressedImage topics, paired by
                         header.stamp within --pair-tolerance-ms
  -o OUT.mcap            depth into an MCAP log (ROS 2 CDR, ros2msg schemas): /curvestereo/depth,
                         camera_info, points, confidence (and depth_pinhole with --pinhole);
                         any other -o is a folder of OUTDIR/<t_ns>/ as for --sequence
  --compression C        the MCAP log's chunks: zstd (default), lz4 or none
)",
     true, false},
    {"log", "list a recorded log's topics, or write a sequence's images as a log",
     R"(usage: curvestereo log info FILE
       curvestereo log info FILE --time-read --topics LEFT,RIGHT [--solve-ms S] [--read-threads N]
       curvestereo log write --sequence SRC -o FILE.mcap [--topics LEFT,RIGHT] [--format raw|png]
                             [--compression zstd|lz4|none]

info: the log's format, and each topic's type, serialisation, message count and rate, and
the time range (log times). FILE: an MCAP file, a ROS 1 bag (2.0), a rosbag2 .db3 or bag
folder. A log cut short is listed up to the cut, with a warning saying where.
With --time-read: the time to open the log as two topics' frames (run --log's opening), to
read (decode) every frame in order on one thread, in ms a frame, and then how long run's
solving thread would wait for frames read ahead (--read-threads, as run) when a frame takes
S ms to solve (--solve-ms, default 2.5, a GPU's warm frame; simulated by waiting).

write: a sequence's image pairs (an ASL folder or "LEFT,RIGHT" folders, as run --sequence)
into an MCAP log, each message stamped with its frame's timestamp (ns).
  --topics LEFT,RIGHT    the topic names (default /cam0/image_raw,/cam1/image_raw)
  --format raw|png       sensor_msgs/Image mono8 (mono16 for 16-bit PNGs; default) or
                         sensor_msgs/CompressedImage holding each PNG file
  --compression C        zstd (default), lz4 or none
)",
     false, false},
    {"eval", "accuracy against ground truth: pairs, baselines, parameter studies, sequences",
     R"(usage: curvestereo eval PAIRDIR... --csv FILE [--md FILE] [--maps DIR] [--methods LIST] [--sparsification FILE]
                         [solver options]
       curvestereo eval PAIRDIR... --sweep warps=A..B|dumax=A..B --csv FILE [--warps-list 5,10,20] [--step X]
       curvestereo eval --sequence DIR... [--cold | --compare] [--blind] [--frames N] [--csv FILE] [--md FILE]
       curvestereo eval RIGDIR [--csv FILE] [--maps DIR] [--pairs I-J,... | --partners N]
                         [--cross-check T] [--panorama-min-confidence C] [--whole-images] [--one-way]
                         [solver options]

A PAIRDIR holds left.png, right.png, camchain.yaml and depth_left.exr (optional
depth_right.exr for the non-occluded scores), as `curvestereo synth` writes it.
The CSV's columns: pair,method,tau1,tau3,epe,tau1_noc,tau3_noc,epe_noc,absrel,density,ms,sky
(sky: the percent of ground-truth sky pixels at +inf or invalid; NaN without sky).
A RIGDIR holds cam<k>.png, depth<k>.exr, camchain.yaml and panorama_range.exr: each camera's
tau over the pixels a partner sees, the panorama's abs-rel where the truth is finite and its
coverage of the sphere two cameras see (docs/guide.md "eval").

  --csv FILE             the results table (required for pairs)
  --md FILE              the same as a Markdown table
  --maps DIR             a picture sheet per pair: input, ground truth, each method's depth
                         and its error map
  --sparsification FILE  ours's pixels ranked by its confidence: tau>1 of the most confident
                         100..50 % beside the oracle's (ranked by true error), the curves' area
                         and the ratio at 80 %, as CSV FILE and a plot FILE's .png
  --methods LIST         comma-separated, default ours: ours, rectified-tgv[-FOV] (the same
                         solver on perspective-rectified images), planesweep, planesweep-valid
                         (with a left-right check), opencv-sgbm[-FOV] (built with OpenCV), all
  --fov LIST             rectified-tgv's fields of view in degrees (default 90,165)
  --sgbm-fov LIST        opencv-sgbm's fields of view (default 120)
  --ps-scale S  --ps-window N  --ps-step PX  --min-depth M
                         the planesweep baseline: working scale (1), ZNCC window (7),
                         image motion between hypotheses (1 px), nearest sphere (0.8 m)
parameter studies (the paper's two):
  --sweep warps=A..B     error and time against the warps per level N = A..B
  --sweep dumax=A..B     error against du_max from A to B in steps of --step X (default 0.1),
                         for each N of --warps-list (default 5,10,20)
  --plot FILE            the study's line plot (default: the CSV's name with .png)
  --replot on            redraw the plot from an existing --csv without solving
sequences (synth --sequence's layout, with ground truth):
  --sequence DIR         tau per frame, on the moving object, and flicker
  --cold                 every frame solved alone
  --compare              cold, then warm, and the ratios
  --blind                the solver gets no poses (a camera without odometry)
  --frames N             the first N frames only (default: all)
  --calib CALIB          instead of the sequence's camchain.yaml
)",
     true, false},
    {"bench", "time per frame and per stage",
     R"(usage: curvestereo bench [--calib CALIB LEFT RIGHT | --size WxH] [--runs N] [--outputs depth|all] [solver options]
       curvestereo bench --sequence SRC [--calib CALIB] [--poses FILE] [--runs N] [solver options]
       curvestereo bench --calib RIG IMG0 IMG1 IMG2 ... [--runs N] [--serial] [rig options]

Times frames after one warm-up frame and prints the median, min and max per frame and per
stage, with the device, the settings and the frame's buffer memory. With one image per
camera of a rig (three or more), a frame is every pair solved and the panorama fused
(--pairs, --partners, --panorama-width, --cross-check, --whole-images, --one-way as for run).

  --calib CALIB LEFT RIGHT   a calibrated pair (default: a rendered 800x800 pair)
  --size WxH             the rendered pair's size (default 800x800)
  --scale-intrinsics     as for run
  --runs N               timed frames (default 50 on a GPU, 3 on the CPU; for --sequence,
                         passes over the sequence: 5 on a GPU, 1 on the CPU)
  --outputs depth|all    depth: radial depth and the valid mask come back (default); all:
                         also disparity, warp, points and confidence
  --sequence SRC  --poses FILE   a sequence's frames through Stereo::next (see run --help)
  --serial               a rig's solves one after the other (default: concurrently)
)",
     true, false},
    {"fields", "write the valid mask, the calibration field and the trajectory field",
     R"(usage: curvestereo fields --calib CALIB -o OUTDIR [--max-fov DEG] [--epipole DEG]

Writes mask.png, calibration.flo / .png (where image 1 is sampled for each pixel of image
0) and trajectory.flo / .png (the epipolar curve's unit tangent) into OUTDIR.

  --calib CALIB          any calibration format run reads
  -o, --output DIR       the output folder
  --max-fov DEG          the field of view used, degrees (default 180; 0: all the model holds)
  --epipole DEG          rays this close to the baseline are invalid, degrees (default 3)
)",
     false, false},
    {"calib", "convert calibration files between Kalibr, Basalt, OpenCV, ORB-SLAM3 and VINS-Fusion, or show one",
     R"(usage: curvestereo calib convert IN OUT [--format kalibr|basalt|opencv|orbslam3|vins] [--image-size WxH]
       curvestereo calib show IN [--image-size WxH]

convert: rewrites IN in another format, chosen by --format or by OUT's name (.json: Basalt,
*camchain*.yaml: Kalibr, .xml: OpenCV; any other name needs --format). A camera model the
target format cannot hold is refused before anything is written.
show: prints the format read, both cameras' models and parameters, the baseline and the pose;
for a rig of more than two cameras also each camera's place, every pair's overlap and the
pairs run solves.
--image-size: the images' size for a file that holds none (OpenCV lists, ORB-SLAM3).
See docs/calibration.md for every format and an example of each.
)",
     false, false},
    {"synth", "render a synthetic pair or sequence with exact ground truth",
     R"(usage: curvestereo synth -o OUTDIR [--scene urban|indoor] [--motion binocular|forward|sideways] [options]
       curvestereo synth --sequence -o OUTDIR [--frames N] [--fps F] [--speed V] [--turn D] [--mover on|off] [options]
       curvestereo synth --rig back2|ring4|ring6 -o OUTDIR [--panorama-width W] [options]

A pair: left.png, right.png, camchain.yaml, depth_left.exr, depth_right.exr (radial metres,
+inf sky, 0 outside the image circle). A sequence: the ASL layout (mav0/cam0, mav0/cam1,
mav0/depth0, poses_cam0.csv, camchain.yaml) of a walking rig, with a moving object's masks.
A rig: cam<k>.png, depth<k>.exr, camchain.yaml, panorama_range.exr, panorama.png and rig.json
(the layout of ../shared/data/rigs, which eval RIGDIR scores; docs/guide.md "synth --rig").

  -o, --output DIR       the output folder
  --scene urban|indoor   the procedural scene (default urban)
  --seed N               the scene's random seed (default 1)
  --size N               image side in pixels (default 800; a sequence 400)
  --samples N            samples per pixel and axis, 1..16 (default 3; a sequence 2)
  --nearest M            the nearest object's distance in metres (default 2)
  --motion binocular|forward|sideways   where camera 1 is (default binocular)
  --baseline M           camera 1's distance (default 0.12)
  --rotation DEG         camera 1 turned about camera 0's y axis (default 0)
  --fov DEG              the rendered field of view (default 180)
  --calib CALIB          render through this rig's cameras instead (--size scales it; not
                         with --motion, --baseline, --rotation)
  --quiet                no progress display
sequences:
  --sequence             render a sequence instead of a pair
  --frames N (12)  --fps F (30)  --speed M/S (1)  --turn DEG/S (20)  --mover on|off (on)
rigs (clean images; --size, --samples, --seed, --scene, --nearest as above, --nearest 1 by default):
  --rig LAYOUT           back2: two 220 deg fisheyes back to back, 12 cm apart;
                         ring4: four 180 deg fisheyes facing front/right/back/left on a 16 cm
                         square, 5 deg down; ring6: six 180 deg fisheyes, a triple 30 deg up
                         (yaw 0/120/240) and a triple 30 deg down (yaw 60/180/300), 8 cm out
  --panorama-width W     the ground-truth panorama's width, even (default 2048; height W/2)
)",
     false, true},
};

const char* kCameraText = R"(camera-model options (off unless asked; depth untouched; writes photometry.json):
  --camera none|t265     a profile (t265: dark, vignetted, noisy, 8 bits), then overrides:
  --exposure MEDIAN      the left image's median grey (0: as rendered)
  --vignette RIM         both cameras' rim/centre in (0, 1]; --vignette-left, --vignette-right
  --vignette-mode radius|angle
  --gain-left G  --gain-right G  --offset-left O  --offset-right O
  --camera-gamma G       response I^(1/G)
  --blur SIGMA_PX        Gaussian optics blur
  --shot S  --read R     noise variance S*I + R^2 in 8-bit grey levels
  --bits 8|16            the PNGs' bit depth
  --noise-seed N         default: the scene's --seed
)";

const CommandText* find(const std::string& name) {
  for (const CommandText& c : kCommands)
    if (name == c.name) return &c;
  return nullptr;
}

}  // namespace

std::string overviewHelp() {
  std::string s = "usage: curvestereo <command> [options]\n\ncommands:\n";
  for (const CommandText& c : kCommands) {
    std::string name = std::string("  ") + c.name;
    name.resize(10, ' ');
    s += name + c.summary + "\n";
  }
  s += "\n'curvestereo <command> --help' prints a command's options; 'curvestereo --version' the version.\n"
       "Exit status: 0 done, 1 an error in the inputs or while solving, 2 a malformed command line.\n";
  return s;
}

std::string commandHelp(const std::string& command) {
  const CommandText* c = find(command);
  if (!c) return {};
  std::string s = c->text;
  if (c->camera) s += std::string("\n") + kCameraText;
  if (c->solver) s += "\n" + solverUsage();
  return s;
}

std::string versionText() { return std::string("curvestereo ") + CURVESTEREO_VERSION; }

}  // namespace cs::cli
