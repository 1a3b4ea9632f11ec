#!/usr/bin/env python3
"""Runs every command the documents show, on the current tree.

    scripts/check-doc-commands.py [--list] [--no-build] [--manual] [FILE...]

Where commands are found (the convention every document follows):
- Markdown (README.md, ARCHITECTURE.md, docs/**/*.md, scenes/*.md,
  deploy/**/*.md, fuzz/README.md): every line of a fenced block whose info
  string is `sh` is a command (`\\` continues a line; `#` lines are
  comments). `sh needs-shared` marks a block that needs the course data:
  it runs only when GLINT_SHARED is set, and its text must say so. Commands
  of other systems (docker, kubectl, sbatch) go in `text` blocks: they are
  shown, not run here (tests/pieces.rs runs the deployment files).
  `sh manual` marks a benchmark of minutes to hours, or a tool that needs
  what CI does not install (its text says what): in CI its script must
  exist and parse (`bash -n`, `python3 -m py_compile`); `--manual` runs it.
- Markdown prose: every inline code span that starts with a command
  (glint, raytracer, cargo, python3, bash, a script under scripts/, after
  optional VAR=value words) is checked as what it is:
  - a synopsis (placeholders: an ALL-CAPS word, `[`, `|`, `<`, `...`):
    shown, not run;
  - a name (`glint render`, `glint bench rays`): a glint subcommand's
    `--help` must exit 0; a script's name alone (or `scripts/`) must exist;
  - a flag mention (`glint render --integrator path`, `raytracer -stats`,
    no input file): every flag must be in that command's help text, and a
    `--help`/`-help` span is run;
  - cargo's checks (`cargo test`, `fmt`, `clippy`, `doc`): CI runs them, so
    the subcommand must be in .ci/run; `cargo install`, `cargo fuzz`,
    `cargo mutants`, `pip install`, `apt-get`: installation steps or other
    tools, shown, not run;
  - anything else is a complete command: run as a block's line (a `serve`
    or `-gui` command as a server). A complete command that needs the
    course data or runs for minutes belongs in a fenced block with its mark.
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
    """(command, needs, where) for each line of the sh blocks; needs is
    False, "shared" or "manual"."""
    cmds, block, shared, cont = [], None, False, ""
    for n, line in enumerate(open(path, encoding="utf-8"), 1):
        stripped = line.strip()
        if block is None:
            m = re.match(r"^\s*```(\S*)\s*(.*)$", line)
            if m:
                block = m.group(1)
                marks = m.group(2).split()
                shared = ("manual" if "manual" in marks else
                          "shared" if "needs-shared" in marks else False)
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


PROGRAMS = ("glint", "raytracer", "cargo", "python3", "bash", "pip", "apt-get")
ENV_WORD = re.compile(r"^[A-Z][A-Z0-9_]*=\S*$")
PLACEHOLDER = re.compile(r"^[A-Z][A-Z0-9_]*$")


def inline_spans(path):
    """(span, where) for each inline code span of the prose (outside fenced
    blocks) that starts with a command."""
    out, fenced = [], False
    for n, line in enumerate(open(path, encoding="utf-8"), 1):
        if line.strip().startswith("```"):
            fenced = not fenced
            continue
        if fenced:
            continue
        for m in re.finditer(r"`([^`]+)`", line):
            span = m.group(1).strip()
            words = span.split()
            while words and ENV_WORD.match(words[0]):
                words = words[1:]
            if words and (words[0] in PROGRAMS or words[0].startswith(("scripts/", "./scripts/"))) \
                    and (len(words) > 1 or words[0].startswith(("scripts/", "./scripts/"))):
                out.append((span, f"{rel(path)}:{n}"))
    return out


def classify(span):
    """What an inline command is (see the module documentation): synopsis,
    name, mention, ci, setup or complete; with the program and its
    subcommand words."""
    words = span.split()
    while words and ENV_WORD.match(words[0]):
        words = words[1:]
    prog, rest = words[0], words[1:]
    if re.search(r"[\[\]<>|…σ]|\.\.\.", span) or any(PLACEHOLDER.match(w) for w in rest):
        return "synopsis", prog, []
    if prog == "cargo":
        sub = rest[0] if rest else ""
        if sub in ("test", "fmt", "clippy", "doc"):
            return "ci", prog, [sub]
        if sub in ("install", "fuzz", "mutants"):
            return "setup", prog, [sub]
        if len(rest) == 1:
            return "name", prog, [sub]
        return "complete", prog, []
    if prog in ("pip", "apt-get"):
        return "setup", prog, []
    if prog in ("glint", "raytracer"):
        subs = []
        if prog == "glint":
            while rest and re.fullmatch(r"[a-z][a-z-]*", rest[0]) and len(subs) < 2:
                subs.append(rest.pop(0))
        if any(w in ("-input", "-i") or "/" in w
               or re.search(r"\.(txt|obj|ply|gltf|glb|png|exr|tga|ppm|pfm|json)$", w) for w in rest):
            return "complete", prog, subs
        return ("name" if not rest else "mention"), prog, subs
    if prog.startswith(("scripts/", "./scripts/")) and not rest:
        return "script", prog, []
    return "complete", prog, []


def help_text(bin_dir, prog, subs):
    """The help text of `glint SUBS...` (its deepest subcommand that
    exists) or of `raytracer`; None when the subcommand does not exist."""
    if prog == "raytracer":
        cmd = [os.path.join(bin_dir, "raytracer"), "-help"]
    else:
        cmd = [os.path.join(bin_dir, "glint")] + subs + ["--help"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0 and prog == "glint" and len(subs) > 1:
        # `glint bench rays` names the bench subcommand's rays mode.
        return help_text(bin_dir, prog, subs[:1])
    return p.stdout if p.returncode == 0 else None


def check_inline(span, where, bin_dir):
    """Checks an inline span that is not run as a command: None when it
    holds, else why not."""
    kind, prog, subs = classify(span)
    if kind in ("synopsis", "setup"):
        return None
    if kind == "script":
        exists = os.path.isdir if prog.endswith("/") else os.path.isfile
        return None if exists(os.path.join(ROOT, prog)) else f"`{span}`: no such file or folder"
    if kind == "ci":
        ci = open(os.path.join(ROOT, ".ci", "run"), encoding="utf-8").read()
        if not re.search(rf"^\s*(\w+=(\"[^\"]*\"|\S+)\s+)*cargo {subs[0]}\b", ci, re.M):
            return f"`{span}`: .ci/run does not run cargo {subs[0]}"
        return None
    if prog == "cargo":
        return None
    text = help_text(bin_dir, prog, subs)
    if text is None:
        return f"`{span}`: {prog} {' '.join(subs)} is not a command (its --help fails)"
    if kind == "mention":
        words = span.split()
        for w in words:
            if w.startswith("-") and w not in ("-", "--"):
                flag = w.split("=", 1)[0]
                if not re.search(rf"(?<![\w-]){re.escape(flag)}(?![\w-])", text):
                    return f"`{span}`: {flag} is not in `{prog} {' '.join(subs)}` help"
    return None


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


def check_manual(cmd):
    """A manual command's script exists and parses; None when it does."""
    words = [w for w in cmd.split() if not ENV_WORD.match(w)]
    script = next((w for w in words if w.startswith(("scripts/", "./scripts/"))), None)
    if script is None:
        return f"a manual command names no script under scripts/: {cmd}"
    path = os.path.join(ROOT, script)
    if not os.path.isfile(path):
        return f"{script} does not exist"
    check = (["python3", "-m", "py_compile", path] if script.endswith(".py")
             else ["bash", "-n", path])
    p = subprocess.run(check, capture_output=True, text=True)
    if p.returncode != 0:
        return f"{script} does not parse: {p.stderr.strip()[-200:]}"
    return None


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

    cmds, spans = [], []
    for md in markdown_files():
        cmds += from_markdown(md)
        spans += inline_spans(md)
    # Complete inline commands run as a block's lines do.
    for span, where in spans:
        kind, prog, subs = classify(span)
        if kind == "complete":
            server = (prog == "glint" and subs[:1] == ["serve"]) or "-gui" in span.split()
            cmds.append((span + ("   # runs until stopped" if server else ""), False, where))
    spans = [(sp, w) for sp, w in spans if classify(sp)[0] != "complete"]
    cmds += from_scene_headers()
    if not listing:
        cmds += from_help(bin_dir)
    if only:
        cmds = [c for c in cmds if any(c[2].startswith(o) for o in only)]
        spans = [c for c in spans if any(c[1].startswith(o) for o in only)]
    if listing:
        for cmd, needs, where in cmds:
            mark = {"shared": "[needs GLINT_SHARED] ", "manual": "[manual] "}.get(needs, "")
            print(f"{where}: {mark}{cmd}")
        for span, where in spans:
            print(f"{where}: [{classify(span)[0]}] {span}")
        return

    changed0, files0 = git_state()
    snap0 = tracked_snapshot(subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True,
                                            text=True).stdout.split())
    failures, ran, skipped = [], 0, []
    env = env_with(bin_dir)
    checked = 0
    for span, where in spans:
        why = check_inline(span, where, bin_dir)
        checked += 1
        if why:
            failures.append(f"{where}: {why}")
    manual_run = "--manual" in args
    try:
        for cmd, needs, where in cmds:
            if needs == "manual" and not manual_run:
                why = check_manual(cmd)
                if why:
                    failures.append(f"{where}: {why}")
                skipped.append(f"{where}: manual (its script parses; --manual runs it): {cmd}")
                continue
            if needs == "shared" and not shared:
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
    print(f"{ran} documented commands run, {checked} inline names and flags checked, "
          f"{len(skipped)} skipped, {len(failures)} failed")
    for f in failures:
        print(f"FAILED {f}", file=sys.stderr)
    if failures:
        sys.exit(1)


if __name__ == "__main__":
    main()
