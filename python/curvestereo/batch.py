"""Many recorded logs through curvestereo on a Dask cluster, one task per recording.

    python3 -m curvestereo.batch LOG... -o OUTDIR --calib CALIB --topics LEFT,RIGHT
                                 [--gpus N | --workers N | --scheduler ADDRESS]
                                 [--frames-per-task N] [--cli PATH] [-- RUN OPTIONS...]

Each log becomes OUTDIR/<log name>.mcap (the depth log of `curvestereo run --log`), written
under a temporary name and renamed when complete, so a rerun skips the recordings already
done and redoes those a crash or a failure left unfinished. A recording that fails is
reported with the command's one-line error and does not stop the others. GPUs are Dask
worker resources: --gpus N starts a local cluster of N workers, one per GPU (each task sees
its worker's GPU alone, through CUDA_VISIBLE_DEVICES); --scheduler joins a running cluster,
whose GPU workers declare `--resources GPU=1` (tasks then ask for one GPU each unless
--no-gpu). Each task runs the `curvestereo` command (which reads frames ahead of the solve)
in its own process, so a crash costs that recording alone. --frames-per-task N cuts each
recording into parts of N frames, a task each, OUTDIR/<log name>.A-B.mcap (frames A to B-1;
each part starts cold). Options after `--` go to `curvestereo run` (e.g. -- --preset fast).
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

SUMMARY = re.compile(r"^(\d+) frames in ([0-9.]+) s:", re.MULTILINE)


class BatchError(Exception):
    """A problem with the batch as a whole (not one recording): one line, exit status 2."""


@dataclass(frozen=True)
class Job:
    log: str
    output: str  # the final .mcap; the temporary one is beside it
    frames: str = ""  # "FIRST:END" for a part of the recording, "" for all of it

    def name(self):
        return self.log + (f" [{self.frames}]" if self.frames else "")


@dataclass
class Outcome:
    log: str
    status: str  # "done", "skipped" (its output was there) or "failed"
    frames: int = 0
    seconds: float = 0.0
    message: str = ""


def partial_path(output):
    """Where a recording's depth is written until complete: hidden, beside the output."""
    out = Path(output)
    return str(out.with_name("." + out.name + ".partial.mcap"))


def plan(logs, out_dir):
    """One job per log; two logs of one name would overwrite each other's output."""
    jobs, seen = [], {}
    for log in logs:
        name = Path(log.rstrip("/")).name
        stem = name[: -len(Path(name).suffix)] if Path(name).suffix else name
        if stem in seen:
            raise BatchError(f"logs {seen[stem]} and {log} would both write {stem}.mcap: give them different names")
        seen[stem] = log
        jobs.append(Job(log, str(Path(out_dir) / f"{stem}.mcap")))
    return jobs


def last_line(text):
    lines = [line for line in text.splitlines() if line.strip()]
    return lines[-1] if lines else ""


def solve(job, cli, calib, topics, run_args, gpu_of_worker):
    """One recording (runs on a Dask worker): `curvestereo run --log` into the temporary
    name, renamed when the command succeeds. Returns an Outcome; never raises for a bad log."""
    env = dict(os.environ)
    if gpu_of_worker:  # a local cluster: worker k owns GPU k
        from distributed import get_worker

        env["CUDA_VISIBLE_DEVICES"] = str(get_worker().name)
    partial = partial_path(job.output)
    command = [cli, "run", "--log", job.log, "--topics", topics, "--calib", calib, "-o", partial, *run_args]
    if job.frames:
        command += ["--frames", job.frames]
    start = time.monotonic()
    proc = subprocess.run(command, capture_output=True, text=True, env=env)
    seconds = time.monotonic() - start
    if proc.returncode != 0:
        Path(partial).unlink(missing_ok=True)
        message = last_line(proc.stderr) or f"curvestereo exited with status {proc.returncode}"
        message = message.removeprefix("curvestereo: ").removeprefix("error: ")
        return Outcome(job.name(), "failed", seconds=seconds, message=message)
    os.replace(partial, job.output)  # complete: a rerun skips it
    match = SUMMARY.search(proc.stdout)
    return Outcome(job.name(), "done", frames=int(match.group(1)) if match else 0, seconds=seconds)


def count_frames(log, topics):
    """A recording's stereo frames, or the one-line error opening it gave (runs on a worker:
    opening a log reads all its headers)."""
    import curvestereo as cs

    left, right = topics.split(",", 1)
    try:
        return len(cs.Sequence.from_log(log, (left, right)))
    except cs.Error as e:
        return Outcome(log, "failed", message=str(e))


def parts(job, frames, per_task):
    """The jobs of a recording cut into runs of per_task frames, each into OUT/<name>.A-B.mcap
    (each part starts cold: the warm start does not cross a cut)."""
    stem = job.output[: -len(".mcap")]
    return [Job(job.log, f"{stem}.{a}-{min(a + per_task, frames)}.mcap", f"{a}:{min(a + per_task, frames)}")
            for a in range(0, frames, per_task)]


def find_cli(given):
    for candidate in (given, os.environ.get("CURVESTEREO_CLI"), shutil.which("curvestereo")):
        if candidate and Path(candidate).is_file() and os.access(candidate, os.X_OK):
            return str(Path(candidate).resolve())
    raise BatchError("the curvestereo command was not found: give --cli PATH or set CURVESTEREO_CLI")


def start_client(args, scratch):
    """A Dask client: a running cluster's, or a local cluster of one worker per GPU (or
    --workers CPU workers). Workers are processes: a solve holds its worker's core(s). The
    local workers keep their files in `scratch` (removed afterwards), not in Dask's default
    dask-worker-space of the working folder or /tmp, which outlives the run."""
    import dask
    from distributed import Client, LocalCluster

    dask.config.set({"temporary-directory": scratch})  # the workers' and the scheduler's lock files too
    # Each task picks its GPU itself (CUDA_VISIBLE_DEVICES); Dask's own NVML monitor is not
    # needed, and Debian 12's distributed (2022.12) fails to start a cluster with it where a
    # newer pynvml is installed (nvmlDeviceGetName returns str; it calls .decode()). Set in
    # the environment too, which the worker processes inherit.
    os.environ["DASK_DISTRIBUTED__DIAGNOSTICS__NVML"] = "False"
    dask.config.set({"distributed.diagnostics.nvml": False})
    if args.scheduler:
        return Client(args.scheduler, timeout="20s"), None
    n = args.gpus or args.workers
    resources = {"GPU": 1} if args.gpus else None
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, resources=resources,
                           dashboard_address=None, local_directory=scratch)
    return Client(cluster), cluster


class Progress:
    """A bar on stderr, redrawn in place on a terminal, a line per recording otherwise."""

    def __init__(self, total, stream=sys.stderr):
        self.total, self.done, self.stream = total, 0, stream
        self.tty = stream.isatty()

    def __call__(self, outcome):
        self.done += 1
        filled = 30 * self.done // max(1, self.total)
        bar = "#" * filled + "." * (30 - filled)
        line = f"[{bar}] {self.done}/{self.total} {outcome.status} {Path(outcome.log).name}"
        if self.tty:  # in place; the last one stays
            self.stream.write("\r" + line + "\033[K" + ("\n" if self.done == self.total else ""))
        else:
            self.stream.write(line + "\n")
        self.stream.flush()


def run_jobs(client, jobs, args, run_args, cli):
    """Submits the unfinished jobs and gathers their outcomes as they complete. With
    --frames-per-task, each recording's frames are counted first (a task each), and its
    parts are submitted as its count arrives."""
    from distributed import as_completed

    outcomes, progress = [], Progress(len(jobs))  # a recording counts one until cut into parts
    use_gpu = bool(args.gpus) or (bool(args.scheduler) and not args.no_gpu)
    pending = {}  # future key -> ("solve" | "count", job)
    queue = as_completed()

    def submit(todo):
        for job in todo:
            if Path(job.output).exists():
                outcomes.append(Outcome(job.name(), "skipped"))
                progress(outcomes[-1])
                continue
            future = client.submit(solve, job, cli, args.calib, args.topics, run_args, bool(args.gpus), pure=False,
                                   resources={"GPU": 1} if use_gpu else None)
            pending[future.key] = ("solve", job)
            queue.add(future)

    if args.frames_per_task:
        for job in jobs:
            future = client.submit(count_frames, job.log, args.topics, pure=False)
            pending[future.key] = ("count", job)
            queue.add(future)
    else:
        submit(jobs)
    for future in queue:
        kind, job = pending.pop(future.key)
        try:
            result = future.result()
        except Exception as e:  # a log that cannot be opened, or a worker lost: this job alone
            result = Outcome(job.name(), "failed", message=f"{e}".splitlines()[0] if str(e) else type(e).__name__)
        if kind == "count" and not isinstance(result, Outcome):
            todo = parts(job, result, args.frames_per_task)
            progress.total += len(todo) - 1
            submit(todo)
            continue
        outcomes.append(result)
        progress(result)
    return outcomes


def summary(outcomes, wall_seconds, unit="recordings"):
    """The report: a line per failure, then the counts and the overall frames per second."""
    failed = [f"failed: {o.log}: {o.message}" for o in outcomes if o.status == "failed"]
    done = [o for o in outcomes if o.status == "done"]
    frames = sum(o.frames for o in done)
    skipped = sum(o.status == "skipped" for o in outcomes)
    return "\n".join(failed + [
        f"{len(done)} {unit} done, {skipped} skipped (already written), {len(failed)} failed; "
        f"{frames} frames in {wall_seconds:.1f} s: {frames / max(wall_seconds, 1e-9):.1f} frames/s overall"])


def parse(argv):
    if "--" in argv:
        cut = argv.index("--")
        argv, run_args = argv[:cut], argv[cut + 1:]
    else:
        run_args = []
    p = argparse.ArgumentParser(prog="python3 -m curvestereo.batch",
                                description="Recorded logs through curvestereo run --log on a Dask cluster.")
    p.add_argument("logs", nargs="+", metavar="LOG", help="MCAP files, ROS 1 bags, rosbag2 .db3 files or folders")
    p.add_argument("-o", "--output", required=True, help="the folder of depth logs, OUTPUT/<log name>.mcap")
    p.add_argument("--calib", required=True, help="the rig's calibration, as curvestereo run --calib")
    p.add_argument("--topics", required=True, help="LEFT,RIGHT image topics, as curvestereo run --topics")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--gpus", type=int, default=0, help="a local cluster, one worker per GPU")
    where.add_argument("--workers", type=int, default=0, help="a local cluster of CPU workers (default 1)")
    where.add_argument("--scheduler", help="a running Dask cluster's address (tcp://host:8786)")
    p.add_argument("--no-gpu", action="store_true", help="with --scheduler: tasks ask for no GPU resource")
    p.add_argument("--cli", help="the curvestereo command (default: $CURVESTEREO_CLI, then PATH)")
    p.add_argument("--frames-per-task", type=int, default=0, metavar="N",
                   help="cut each recording into parts of N frames, a task each, into OUTPUT/<log name>.A-B.mcap")
    args = p.parse_args(argv)
    if args.gpus < 0 or args.workers < 0 or args.frames_per_task < 0:
        p.error("--gpus, --workers and --frames-per-task take a positive count")
    if not args.gpus and not args.scheduler and not args.workers:
        args.workers = 1
    return args, run_args


def main(argv=None):
    args, run_args = parse(sys.argv[1:] if argv is None else argv)
    try:
        cli = find_cli(args.cli)
        missing = [log for log in args.logs if not Path(log).exists()]
        if missing:
            raise BatchError(f"log {missing[0]} does not exist")
        Path(args.output).mkdir(parents=True, exist_ok=True)
        jobs = plan(args.logs, args.output)
    except (BatchError, OSError) as e:
        print(f"curvestereo.batch: {e}", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory(prefix="curvestereo-batch-") as scratch:
        try:
            client, cluster = start_client(args, scratch)
        except (OSError, TimeoutError) as e:  # an unreachable scheduler, no port to listen on
            where = args.scheduler or "a local cluster"
            print(f"curvestereo.batch: cannot start or reach {where}: {str(e).splitlines()[0]}", file=sys.stderr)
            return 2
        start = time.monotonic()  # the throughput is the solving's, not the cluster's start-up
        try:
            outcomes = run_jobs(client, jobs, args, run_args, cli)
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    print(summary(outcomes, time.monotonic() - start, "parts" if args.frames_per_task else "recordings"))
    return 1 if any(o.status == "failed" for o in outcomes) else 0


if __name__ == "__main__":
    sys.exit(main())
