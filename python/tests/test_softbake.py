"""The Python module against the command line (ctest: python_tests).

ctest sets PYTHONPATH to the built module and SOFTBAKE_BINARY to the `softbake` command of the
same build; by hand, from the repository root:

    PYTHONPATH=build/python python3 -m pytest -q python/tests
"""
import _thread
import copy
import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import softbake

SOURCE_DIR = Path(os.environ.get("SOFTBAKE_SOURCE_DIR", Path(__file__).resolve().parents[2]))
EXAMPLES = SOURCE_DIR / "examples"
# The command built with the module: build/cli/softbake beside build/python/softbake*.so.
BINARY = Path(os.environ.get("SOFTBAKE_BINARY",
                             Path(softbake.__file__).resolve().parent.parent / "cli" / "softbake"))

# The built-in scene's balls touch from frame 8 to 11: positions and contacts are compared at 10.
FRAME = 10


def cli(*arguments, check=True):
    """Runs the `softbake` command; returns the finished process (text output)."""
    if not BINARY.is_file():
        pytest.fail(f"no softbake binary at {BINARY} (set SOFTBAKE_BINARY)")
    result = subprocess.run([str(BINARY), *map(str, arguments)], capture_output=True, text=True,
                            timeout=240)
    if check and result.returncode != 0:
        pytest.fail(f"softbake {' '.join(map(str, arguments))} exited {result.returncode}:\n"
                    f"{result.stdout}\n{result.stderr}")
    return result


def cli_error(*arguments):
    """The message `softbake` prints as 'softbake: error: MESSAGE' (exit code 1)."""
    result = cli(*arguments, check=False)
    assert result.returncode == 1, result.stderr
    marker = "softbake: error: "
    return result.stderr[result.stderr.rindex(marker) + len(marker):].rstrip("\n")


def obj_positions(path):
    """{object name: float32 (N, 3) of its `v` lines} of an OBJ frame. The writer prints the
    shortest text that reads back to the same float, so the float32 of each number is exact."""
    bodies, current = {}, None
    for line in Path(path).read_text().splitlines():
        if line.startswith("o "):
            current = bodies.setdefault(line[2:], [])
        elif line.startswith("v "):
            current.append([float(x) for x in line.split()[1:]])
    return {name: np.array(rows, dtype=np.float64).astype(np.float32) for name, rows in bodies.items()}


def bits(array):
    """The array's bytes as integers: equal only when every value is the same float, -0.0 too."""
    array = np.ascontiguousarray(array)
    return array.view(np.uint32 if array.dtype == np.float32 else np.uint64)


@pytest.fixture(scope="module")
def cli_bake(tmp_path_factory):
    """`softbake run` of the built-in scene to frame 10, OBJ and contacts, as the command."""
    out = tmp_path_factory.mktemp("cli")
    cli("run", "default", "--out", out, "--frames", FRAME, "--no-render", "--contacts", "-q")
    return out


@pytest.fixture(scope="module")
def at_frame_10():
    simulation = softbake.Simulation("default")
    simulation.advance(FRAME - 1)
    return simulation


# --- the API ------------------------------------------------------------------------------------

def test_builtin_scene():
    simulation = softbake.Simulation("default")
    assert simulation.frame == 1 and simulation.time == 0
    assert simulation.name == "default"
    assert simulation.bodies == ["ballA", "ballB"]
    assert simulation.frames == 240 and simulation.fps == 24
    assert "default" in softbake.builtin_scenes() and "balls1k" in softbake.builtin_scenes()
    positions = simulation.positions("ballA")
    assert positions.dtype == np.float32 and positions.shape == (642, 3)  # icosphere level 3
    assert not positions.flags.writeable
    # Frame 1 is the initial state: the ball about (-1.2, 1.5, 0), every particle at its velocity.
    assert np.allclose(positions.mean(axis=0), [-1.2, 1.5, 0], atol=1e-3)
    assert np.array_equal(simulation.velocities("ballA"), np.tile(np.float32([2.5, 2.0, 0]), (642, 1)))
    simulation.advance()
    simulation.advance(2)
    assert simulation.frame == 4 and simulation.time == pytest.approx(3 / 24)
    simulation.advance(0)
    assert simulation.frame == 4
    assert "frame 4 of 240" in repr(simulation)


def test_body_by_name_or_index():
    simulation = softbake.Simulation()  # None: the built-in default scene
    assert np.shares_memory(simulation.positions(1), simulation.positions("ballB"))
    assert np.shares_memory(simulation.positions(-1), simulation.positions("ballB"))
    with pytest.raises(KeyError, match="no body 'ballC'.*'ballA', 'ballB'"):
        simulation.positions("ballC")
    with pytest.raises(IndexError, match="body 2: scene 'default' has 2 bodies"):
        simulation.velocities(2)
    with pytest.raises(TypeError):
        simulation.positions(1.0)


def test_scene_file_dict_and_builtin_agree():
    """The same scene as a file, as a dict, and built in: the same simulation, bit for bit."""
    scene = json.loads((EXAMPLES / "default.json").read_text())
    simulations = [softbake.Simulation(EXAMPLES / "default.json"), softbake.Simulation(scene),
                   softbake.Simulation("default")]
    for simulation in simulations:
        simulation.advance(3)
    for body in ("ballA", "ballB"):
        reference = bits(simulations[2].positions(body))
        for simulation in simulations[:2]:
            assert np.array_equal(bits(simulation.positions(body)), reference)


def test_mesh_file_scene():
    simulation = softbake.Simulation(str(EXAMPLES / "sheet_24.obj"))
    assert len(simulation.bodies) == 1
    start = simulation.positions(0).copy()
    simulation.advance(2)
    assert simulation.positions(0)[:, 1].mean() < start[:, 1].mean()  # dropped: it falls


def test_simulation_options():
    simulation = softbake.Simulation("default", frames=10, fps=48, integrator="explicit",
                                     substeps=40, threads=1)
    assert simulation.frames == 10 and simulation.fps == 48
    simulation.advance()
    assert simulation.substeps == 40
    with pytest.raises(TypeError, match="unexpected keyword argument 'vdb'"):
        softbake.Simulation("default", vdb=True)  # an output option: run() only
    with pytest.raises(ValueError, match="integrator: expected 'explicit', 'implicit' or 'xpbd'"):
        softbake.Simulation("default", integrator="verlet")
    with pytest.raises(ValueError, match="frames: expected a whole number from 1 to 10000000"):
        softbake.Simulation("default", frames=0)
    with pytest.raises(ValueError, match="substeps: expected 'auto' or a whole number"):
        softbake.Simulation("default", substeps="many")
    with pytest.raises(TypeError, match="threads: expected a whole number"):
        softbake.Simulation("default", threads=2.5)


def test_contacts_match_the_contact_files(cli_bake, at_frame_10):
    """contacts() lists what the command's contacts JSON holds for the same frame."""
    contacts = at_frame_10.contacts()
    written = json.loads((cli_bake / "contacts" / f"default_{FRAME:04d}.json").read_text())
    assert written["frame"] == FRAME
    assert len(contacts) > 0, "the balls touch at frame 10"
    expected = [{**c, "position": tuple(c["position"]), "normal": tuple(c["normal"]),
                 "bodies": tuple(c["bodies"]), "triangles": tuple(c["triangles"])}
                for c in written["contacts"]]
    assert contacts == expected
    assert {c["kind"] for c in contacts} <= {"edge-triangle", "particle-triangle", "corner", "held"}


# --- bit-identical to the command's OBJ ----------------------------------------------------------

def test_positions_equal_the_cli_obj_bit_for_bit(cli_bake, at_frame_10):
    written = obj_positions(cli_bake / "obj" / f"default_{FRAME:04d}.obj")
    assert list(written) == at_frame_10.bodies
    for body, positions in written.items():
        assert np.array_equal(bits(at_frame_10.positions(body)), bits(positions)), body


def test_run_writes_what_the_cli_writes(cli_bake, tmp_path):
    """softbake.run() is `softbake run`: the same OBJ frames, byte for byte."""
    out = tmp_path / "run"
    assert softbake.run("default", out=out, frames=FRAME, render=False, contacts=True,
                        quiet=True) == 0
    for folder in ("obj", "contacts"):
        names = sorted(p.name for p in (cli_bake / folder).iterdir())
        assert names == sorted(p.name for p in (out / folder).iterdir())
        for name in names:
            assert (out / folder / name).read_bytes() == (cli_bake / folder / name).read_bytes(), name
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["status"] == "complete"
    assert manifest["run"]["options"]["frames"] == FRAME


def test_run_options(tmp_path):
    assert softbake.run(None, out=tmp_path / "a", frames=2, render=False, no_cache=True,
                        frame_padding=3, substeps="auto", threads=1, quiet=True) == 0
    assert (tmp_path / "a" / "obj" / "default_002.obj").is_file()
    assert not (tmp_path / "a" / "cache").exists()
    with pytest.raises(TypeError, match="unexpected keyword argument 'frame'"):
        softbake.run("default", out=tmp_path / "b", frame=2)
    with pytest.raises(ValueError, match="up: expected 'y' or 'z', got 'x'"):
        softbake.run("default", out=tmp_path / "b", up="x")
    with pytest.raises(ValueError, match="checkpoint_every excludes no_cache"):
        softbake.run("default", out=tmp_path / "b", no_cache=True, checkpoint_every=4)
    with pytest.raises(TypeError, match="render: expected true or false"):
        softbake.run("default", out=tmp_path / "b", render="yes")
    assert not (tmp_path / "b").exists()  # refused before anything was written


def test_run_writes_the_bake_report(tmp_path):
    """report= is --report: the report's page, and a record per frame in the output folder."""
    assert softbake.run("default", out=tmp_path / "out", frames=3, render=False, quiet=True,
                        report=tmp_path / "report") == 0
    page = (tmp_path / "report" / "index.html").read_text()
    assert "softbake bake report: default" in page
    records = [json.loads(line) for line in
               (tmp_path / "out" / "frame_stats.jsonl").read_text().splitlines()]
    assert [r["frame"] for r in records] == [1, 2, 3]
    with pytest.raises(TypeError, match="report: expected a path"):
        softbake.run("default", out=tmp_path / "b", report=3)


def test_run_takes_every_flag_of_the_command(tmp_path):
    """Each flag `softbake run --help` lists is a keyword of run() (--no-render is render=False)."""
    flags = re.findall(r"^\s+(?:-\w,)?--([a-z][a-z0-9-]*)", cli("run", "--help").stdout, re.M)
    keywords = {flag.replace("-", "_") for flag in flags} - {"help", "out", "no_render"}
    assert {"frames", "render", "vdb", "resume"} <= keywords
    for keyword in sorted(keywords):
        with pytest.raises((TypeError, ValueError)) as error:  # no option takes an object()
            softbake.run("default", out=tmp_path / "never", **{keyword: object()})
        assert "unexpected keyword" not in str(error.value), f"run() lacks --{keyword}"
    assert not (tmp_path / "never").exists()


# --- errors: the command's messages -------------------------------------------------------------

def test_bad_scene_path_raises_the_cli_message(tmp_path):
    missing = tmp_path / "missing.json"
    expected = cli_error("run", missing, "--out", tmp_path / "cli")
    assert expected.startswith(f"{missing}: no such file, and not a built-in scene (default,")
    with pytest.raises(softbake.Error) as error:
        softbake.Simulation(missing)
    assert str(error.value) == expected
    assert isinstance(error.value, RuntimeError)
    with pytest.raises(softbake.Error) as error:
        softbake.run(missing, out=tmp_path / "py")
    assert str(error.value) == expected
    assert error.value.exit_code == 1  # the command's status for bad input


def test_bad_key_in_a_dict_names_the_key_path(tmp_path):
    scene = json.loads((EXAMPLES / "default.json").read_text())
    scene["bodies"][1]["material"] = {"preset": "rubber", "stiffness": "very"}
    with pytest.raises(softbake.Error) as error:
        softbake.Simulation(scene)
    message = str(error.value)
    assert message.startswith("scene dict: bodies[1].material.stiffness: "), message
    # The same scene as a file: the command says the same after the file's name.
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(scene))
    assert cli_error("run", path, "--out", tmp_path / "out") == f"{path}: {message[len('scene dict: '):]}"

    unknown = copy.deepcopy(scene)
    unknown["bodies"][1]["material"] = "rubber"
    unknown["settings"]["framez"] = 3
    with pytest.raises(softbake.Error, match=r"^scene dict: settings.*framez"):
        softbake.Simulation(unknown)
    with pytest.raises(TypeError, match=r"scene dict: bodies\[0\].velocity\[1\]: set is not JSON"):
        softbake.Simulation({"bodies": [{"velocity": [0, {1}, 0]}]})


def test_dict_takes_numpy_values():
    scene = json.loads((EXAMPLES / "default.json").read_text())
    reference = softbake.Simulation(copy.deepcopy(scene))
    scene["bodies"][0]["velocity"] = np.array([2.5, 2.0, 0.0])
    scene["settings"]["fps"] = np.int64(24)
    simulation = softbake.Simulation(scene)
    reference.advance(2)
    simulation.advance(2)
    assert np.array_equal(bits(simulation.positions(0)), bits(reference.positions(0)))


# --- no copies, no GIL ---------------------------------------------------------------------------

def test_positions_are_a_view_of_the_state():
    simulation = softbake.Simulation("default")
    first, again = simulation.positions("ballA"), simulation.positions("ballA")
    assert np.shares_memory(first, again)
    assert first.ctypes.data == again.ctypes.data and first.strides == (12, 4)
    assert first.base is simulation or first.base.base is simulation
    before = first.copy()
    simulation.advance()
    assert not np.array_equal(first, before), "the view follows the simulation"
    assert np.array_equal(first, simulation.positions("ballA"))
    assert not np.shares_memory(simulation.positions("ballA"), simulation.positions("ballB"))
    velocities = simulation.velocities("ballA")
    del simulation  # the arrays keep it alive
    assert np.isfinite(first).all() and np.isfinite(velocities).all()
    with pytest.raises(ValueError):
        first[0, 0] = 1  # read-only: the simulator owns it


def _refusal(call):
    """The message of the ValueError `call` raised; None when it went through."""
    try:
        call()
    except ValueError as error:
        return str(error)
    return None


def _on_seeing_advance_run(simulation, act, stop):
    """A thread that calls act(refusal) once it sees advance() run on `simulation`, from a call
    that refuses to overlap it, or ends when `stop` is set. That it sees it at all is the proof
    that the GIL was let go: held, it would let this thread in only between two advance() calls,
    when the Simulation is not busy."""
    def watch():
        while not stop.is_set():
            refusal = _refusal(simulation.contacts)
            if refusal is not None:
                act(refusal)
                return

    thread = threading.Thread(target=watch)
    thread.start()
    return thread


def test_advance_releases_the_gil():
    """A Python thread keeps running while advance() simulates."""
    simulation = softbake.Simulation("balls10k")
    refusals, stop = [], threading.Event()
    watcher = _on_seeing_advance_run(simulation, refusals.append, stop)
    frames = 0
    try:
        # A frame at a time, a count and not a time bounding it: the watcher gets its chance
        # in each, and a held GIL fails the test instead of hanging it.
        while watcher.is_alive() and frames < 50:
            simulation.advance(1)
            frames += 1
    finally:
        stop.set()
        watcher.join()
    assert refusals, f"no other thread ran during {frames} frames of advance()"
    assert refusals[0] == "contacts(): advance() is running on this Simulation in another thread"


def test_advance_from_two_threads_is_refused():
    """While advance() runs, the calls of another thread that would overlap it are refused and
    change nothing."""
    simulation = softbake.Simulation("balls10k")
    refused, advanced, stop = {}, {"main": 0, "other": 0}, threading.Event()

    def other():
        while len(refused) < 2 and not stop.is_set():
            refusal = _refusal(simulation.contacts)
            if refusal is None:
                continue
            refused.setdefault("contacts", refusal)
            # The advance() seen keeps the Simulation until it has the GIL back, and this thread
            # keeps the GIL from that call to this one unless Python switches threads in between:
            # then this one runs, a frame of its own.
            refusal = _refusal(lambda: simulation.advance(1))
            if refusal is None:
                advanced["other"] += 1
            else:
                refused.setdefault("advance", refusal)

    thread = threading.Thread(target=other)
    thread.start()
    try:
        # Bounded by frames, not calls: this thread's advance() is refused too while the other's
        # runs, and a frame is done either way.
        while thread.is_alive() and advanced["main"] + advanced["other"] < 100:
            if _refusal(lambda: simulation.advance(1)) is None:
                advanced["main"] += 1
    finally:
        stop.set()
        thread.join()
    assert sorted(refused) == ["advance", "contacts"], (refused, advanced)
    for name, refusal in refused.items():
        assert refusal == f"{name}(): advance() is running on this Simulation in another thread"
    # A refused advance() simulates nothing: every frame is one that a call went through for.
    assert simulation.frame == 1 + advanced["main"] + advanced["other"], advanced


def test_ctrl_c_stops_advance_between_frames():
    simulation = softbake.Simulation("default")
    stop = threading.Event()
    # As Ctrl-C does, once advance() is seen running.
    watcher = _on_seeing_advance_run(simulation, lambda _: _thread.interrupt_main(), stop)
    try:
        with pytest.raises(KeyboardInterrupt):
            simulation.advance(200)
    finally:
        stop.set()
        watcher.join()
    assert 1 < simulation.frame < 201  # the frames done are kept, and it can go on
    frame = simulation.frame
    simulation.advance()
    assert simulation.frame == frame + 1


def test_interrupted_run_resumes(tmp_path, capfd):
    """SIGINT stops softbake.run() after a frame, as it stops the command (exit code 130, the
    resume command printed); resume=True finishes it."""
    out = tmp_path / "out"
    options = dict(frames=12, render=False, quiet=True)

    finished = threading.Event()

    def interrupt():
        # Once frames are written the run's own handler is in place (before, Python's would
        # raise KeyboardInterrupt in the test instead). Polled, for as long as the run lasts: the
        # file appears by a rename in the run's writer thread.
        while not finished.is_set():
            if (out / "obj" / "balls10k_0002.obj").exists():
                os.kill(os.getpid(), signal.SIGINT)
                return
            time.sleep(0.001)

    thread = threading.Thread(target=interrupt)
    thread.start()
    try:
        code = softbake.run("balls10k", out=out, **options)
    finally:
        finished.set()
        thread.join()
    assert code == 130
    stderr = capfd.readouterr().err
    assert f"softbake run balls10k --out {out} --frames 12 --no-render --quiet --resume" in stderr
    assert json.loads((out / "manifest.json").read_text())["status"] == "incomplete"
    assert softbake.run("balls10k", out=out, resume=True, **options) == 0
    assert json.loads((out / "manifest.json").read_text())["status"] == "complete"
    assert cli("verify", out).returncode == 0


def test_version():
    assert softbake.__version__ == cli("--version").stdout.split()[-1]
