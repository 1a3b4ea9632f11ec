#!/usr/bin/env python3
"""Runs every command the documents show, on the current tree.

    scripts/check-doc-commands.py [--list] [--no-build] [FILE...]

Where commands are found (the convention every document follows):
- Markdown (README.md, ARCHITECTURE.md, docs/**/*.md, scenes/*.md,
  deploy/**/*.md, fuzz/README.md): every line of a fenced block whose info
  string is `sh` is a command (`\\` continues a line; `#` lines are
  comments). `sh needs-shared` marks a block that needs the course data:
  it runs only when GLINT_SHARED is set, and its text must say so. Commands
  of other systems (docker, kubectl, sbatch) go in `text` blocks: they are
  shown, not run here (tests/pieces.rs runs the deployment files).
- Scene files (scenes/*.txt): the header line `# Render: COMMAND`.
- `--help` texts: `glint --help`, every subcommand's `--help` and
  `raytracer -help` must print and exit 0; a help line `  $ COMMAND` is a
  command too.
A command ending in `# exits N` must exit with status N; one ending in
`# runs until stopped` (a server) must still be running after 15 seconds,
and is then stopped; every other one must exit with 0.

How they run: from the repository root with `target/release` first on the
PATH (built first unless --no-build), in order, one shell each, so a block's
later lines see its earlier lines' files. Sizes are reduced to keep CI
short: `--size`/`-size W H` scaled so the longer side is at most 48 pixels
(with `--crop` and `--pixel` coordinates scaled alike) and `--spp` capped
at 4. `cargo test` lines are not run (CI runs the tests itself). A command
that changes a tracked file fails; files the commands create are removed
afterwards (never anything under target/).

Exits 1 listing the commands that failed.
"""

import glob
import os
import re
import shlex
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MAX_SIDE = 48
MAX_SPP = 4


def markdown_files():
    pats = ["README.md", "ARCHITECTURE.md", "docs/**/*.md", "scenes/*.md",
            "deploy/**/*.md", "fuzz/README.md"]
    out = []
    for p in pats:
        out += sorted(glob.glob(os.path.join(ROOT, p), recursive=True))
    return out


def from_markdown(path):
    """(command, needs_shared, where) for each line of the sh blocks."""
    cmds, block, shared, cont = [], None, False, ""
    for n, line in enumerate(open(path, encoding="utf-8"), 1):
        stripped = line.strip()
        if block is None:
            m = re.match(r"^\s*```(\S*)\s*(.*)$", line)
            if m:
                block = m.group(1)
                shared = "needs-shared" in m.group(2).split()
            continue
        if stripped.startswith("```"):
            block = None
            continue
        if block != "sh":
            continue
        if not stripped or (stripped.startswith("#") and not cont):
            continue
        if stripped.endswith("\\"):
            cont += stripped[:-1] + " "
            continue
        cmds.append((cont + stripped, shared, f"{rel(path)}:{n}"))
        cont = ""
    return cmds


def from_scene_headers():
    cmds = []
    for path in sorted(glob.glob(os.path.join(ROOT, "scenes/*.txt"))):
        for n, line in enumerate(open(path, encoding="utf-8"), 1):
            m = re.match(r"^#\s*Render:\s*(.+)$", line)
            if m:
                cmds.append((m.group(1).strip(), False, f"{rel(path)}:{n}"))
            if line.strip() and not line.startswith("#"):
                break
    return cmds


def from_help(bin_dir):
    """The help texts themselves, and their `$ ` lines."""
    glint = os.path.join(bin_dir, "glint")
    top = subprocess.run([glint, "--help"], capture_output=True, text=True).stdout
    subs = []
    in_cmds = False
    for line in top.splitlines():
        if line.startswith("Commands:"):
            in_cmds = True
            continue
        if in_cmds:
            m = re.match(r"^  (\S+)\s", line)
            if not m:
                break
            if m.group(1) != "help":
                subs.append(m.group(1))
    helps = ["glint --help"] + [f"glint {s} --help" for s in subs] + ["raytracer -help"]
    cmds = [(h, False, "--help") for h in helps]
    for h in helps:
        text = subprocess.run(shlex.split(h), capture_output=True, text=True,
                              env=env_with(bin_dir)).stdout
        for line in text.splitlines():
            m = re.match(r"^\s+\$ (.+)$", line)
            if m:
                cmds.append((m.group(1), False, f"`{h}`"))
    return cmds


def rel(p):
    return os.path.relpath(p, ROOT)


def reduce(cmd):
    """Scales --size (and the --crop/--pixel coordinates with it) so the
    longer side is at most MAX_SIDE, and caps --spp."""
    m = re.search(r"(?<!\S)(--?size)\s+(\d+)\s+(\d+)", cmd)
    if m:
        w, h = int(m.group(2)), int(m.group(3))
        s = min(1.0, MAX_SIDE / max(w, h))
        if s < 1.0:
            sw, sh = max(1, round(w * s)), max(1, round(h * s))
            cmd = cmd[:m.start()] + f"{m.group(1)} {sw} {sh}" + cmd[m.end():]

            def crop(c):
                x0, y0, x1, y1 = (int(v) for v in c.groups()[1:])
                a, b = int(x0 * s), int(y0 * s)
                return (f"{c.group(1)} {a} {b} {max(a + 1, min(sw, round(x1 * s)))} "
                        f"{max(b + 1, min(sh, round(y1 * s)))}")
            cmd = re.sub(r"(?<!\S)(--crop)\s+(\d+)\s+(\d+)\s+(\d+)\s+(\d+)", crop, cmd)

            def pixel(c):
                x, y = int(c.group(2)), int(c.group(3))
                return f"{c.group(1)} {min(sw - 1, int(x * s))} {min(sh - 1, int(y * s))}"
            cmd = re.sub(r"(?<!\S)(--pixel)\s+(\d+)\s+(\d+)", pixel, cmd)
    cmd = re.sub(r"(?<!\S)(--spp)\s+(\d+)",
                 lambda c: f"{c.group(1)} {min(int(c.group(2)), MAX_SPP)}", cmd)
    return cmd


def env_with(bin_dir):
    env = dict(os.environ)
    env["PATH"] = bin_dir + os.pathsep + env.get("PATH", "")
    return env


def git_state():
    """Tracked files' contents hash and the untracked/ignored files."""
    diff = subprocess.run(["git", "diff", "--name-only"], cwd=ROOT,
                          capture_output=True, text=True).stdout.split()
    others = subprocess.run(["git", "ls-files", "--others", "-z"], cwd=ROOT,
                            capture_output=True, text=True).stdout.split("\0")
    ignored = subprocess.run(["git", "ls-files", "--others", "--ignored",
                              "--exclude-standard", "--directory", "-z"], cwd=ROOT,
                             capture_output=True, text=True).stdout.split("\0")
    return set(diff), {f for f in others + ignored if f}


def tracked_snapshot(names):
    return {n: open(os.path.join(ROOT, n), "rb").read()
            for n in names if os.path.isfile(os.path.join(ROOT, n))}


def main():
    args = sys.argv[1:]
    listing = "--list" in args
    build = "--no-build" not in args
    only = [a for a in args if not a.startswith("--")]
    target = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
    bin_dir = os.path.join(target, "release")
    if build and not listing:
        subprocess.run(["cargo", "build", "--release", "--quiet", "--bins"], cwd=ROOT,
                       check=True)
    # The course data: GLINT_SHARED, else ../shared beside the repository
    # (as src/testdata.rs finds it); the documents write "$GLINT_SHARED".
    if not os.environ.get("GLINT_SHARED"):
        beside = os.path.join(os.path.dirname(ROOT), "shared")
        if os.path.isdir(beside):
            os.environ["GLINT_SHARED"] = beside
    shared = bool(os.environ.get("GLINT_SHARED"))
    if not shared and os.environ.get("GLINT_REQUIRE_SHARED") == "1":
        sys.exit("check-doc-commands: GLINT_REQUIRE_SHARED=1 but no course data (GLINT_SHARED)")

    cmds = []
    for md in markdown_files():
        cmds += from_markdown(md)
    cmds += from_scene_headers()
    if not listing:
        cmds += from_help(bin_dir)
    if only:
        cmds = [c for c in cmds if any(c[2].startswith(o) for o in only)]
    if listing:
        for cmd, needs, where in cmds:
            print(f"{where}: {'[needs GLINT_SHARED] ' if needs else ''}{cmd}")
        return

    changed0, files0 = git_state()
    snap0 = tracked_snapshot(subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True,
                                            text=True).stdout.split())
    failures, ran, skipped = [], 0, []
    env = env_with(bin_dir)
    try:
        for cmd, needs, where in cmds:
            if needs and not shared:
                skipped.append(f"{where}: needs GLINT_SHARED: {cmd}")
                continue
            if re.match(r"^cargo\s+test\b", cmd):
                skipped.append(f"{where}: the test suite (CI runs it): {cmd}")
                continue
            want = 0
            m = re.search(r"#\s*exits\s+(\d+)\s*$", cmd)
            if m:
                want = int(m.group(1))
            run = reduce(cmd)
            ran += 1
            if re.search(r"#\s*runs until stopped\s*$", cmd):
                p = subprocess.Popen(["bash", "-c", run], cwd=ROOT, env=env,
                                     stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                     text=True, start_new_session=True)
                try:
                    _, err = p.communicate(timeout=15)
                    failures.append(f"{where}: exited {p.returncode} instead of running: {run}"
                                    f"\n    {err.strip()[-300:]}")
                except subprocess.TimeoutExpired:
                    os.killpg(p.pid, 15)
                    p.communicate()
                continue
            p = subprocess.run(["bash", "-c", run], cwd=ROOT, env=env,
                               capture_output=True, text=True)
            if p.returncode != want:
                err = (p.stderr.strip() or p.stdout.strip()).splitlines()[-3:]
                failures.append(f"{where}: exit {p.returncode} (expected {want}): {run}\n    "
                                + "\n    ".join(err))
                continue
            for name, before in snap0.items():
                path = os.path.join(ROOT, name)
                now = open(path, "rb").read() if os.path.isfile(path) else None
                if now != before:
                    failures.append(f"{where}: changed the tracked file {name}: {run}")
                    open(path, "wb").write(before)
    finally:
        _, files1 = git_state()
        for f in sorted(files1 - files0):
            path = os.path.join(ROOT, f)
            if f.startswith("target/") or not os.path.exists(path):
                continue
            if os.path.isdir(path) and not os.path.islink(path):
                subprocess.run(["rm", "-rf", path])
            else:
                os.remove(path)
    for s in skipped:
        print(f"skipped {s}")
    print(f"{ran} documented commands run, {len(skipped)} skipped, {len(failures)} failed")
    for f in failures:
        print(f"FAILED {f}", file=sys.stderr)
    if failures:
        sys.exit(1)


if __name__ == "__main__":
    main()
