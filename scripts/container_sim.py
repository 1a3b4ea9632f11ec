#!/usr/bin/env python3
"""Runs the Kubernetes Jobs of deploy/k8s/ as a cluster would, without one.

    scripts/container_sim.py BIN_DIR WORK_DIR [--env NAME=VALUE ...] MANIFEST...

1. The image: the final stage of deploy/Dockerfile is laid out in
   WORK_DIR/root. Each `COPY --from=build SRC... DEST` copies what the build
   stage has at SRC (`/src` is the repository, `/src/target/release/X` is
   BIN_DIR/X); the base image's shell, `mkdir` and the dynamic libraries the
   binaries need are taken from this machine.
2. The volume: every volumeMount's path in the image is replaced by an empty
   folder (a mount hides what the image has there), one per claim, shared by
   every Job and pod, as a PersistentVolumeClaim is.
3. The pods: for each Job (in the order given), each completion index runs
   the container's `command + args` exactly as written, chrooted into the
   image at its WORKDIR, with the container's env, JOB_COMPLETION_INDEX for
   Indexed Jobs and the base image's PATH. `--env NAME=VALUE` replaces the
   value of an env entry the manifest declares (to render a small frame);
   nothing else of the manifest is changed.

Exits non-zero, saying why, if a pod fails; prints the image root. Needs
root (it re-runs itself under `unshare -r` otherwise) and PyYAML.
"""

import os
import shlex
import shutil
import subprocess
import sys

import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# debian:bookworm-slim's PATH.
IMAGE_PATH = "/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin"


def final_stage(dockerfile):
    """The COPY --from=build lines and the WORKDIR of the last stage."""
    lines, cont = [], ""
    for raw in open(dockerfile):
        line = raw.rstrip("\n")
        if line.strip().startswith("#"):
            continue
        if line.endswith("\\"):
            cont += line[:-1] + " "
            continue
        lines.append((cont + line).strip())
        cont = ""
    last = max(i for i, l in enumerate(lines) if l.upper().startswith("FROM "))
    copies, workdir = [], "/"
    for l in lines[last + 1:]:
        words = shlex.split(l)
        if not words:
            continue
        op = words[0].upper()
        if op == "COPY":
            args = words[1:]
            if not args[0].startswith("--from="):
                sys.exit(f"container_sim: the final stage copies from the context: {l}")
            copies.append((args[1:-1], args[-1]))
        elif op == "WORKDIR":
            workdir = os.path.join(workdir, words[1])
    return copies, workdir


def build_source(path, bin_dir):
    """Where the build stage's `path` is on this machine."""
    if path.startswith("/src/target/release/"):
        return os.path.join(bin_dir, os.path.basename(path))
    if path == "/src" or path.startswith("/src/"):
        return os.path.join(ROOT, path[len("/src/"):])
    sys.exit(f"container_sim: the build stage has no {path}")


def inside(root, path):
    return os.path.join(root, path.lstrip("/"))


def copy_libs(root, exe):
    """Copies the shared libraries `exe` loads to the same paths."""
    for f in libraries(exe):
        dest = inside(root, f)
        if not os.path.exists(dest):
            os.makedirs(os.path.dirname(dest), exist_ok=True)
            shutil.copy2(os.path.realpath(f), dest)


def libraries(exe):
    out = subprocess.run(["ldd", exe], capture_output=True, text=True).stdout
    libs = []
    for line in out.splitlines():
        parts = line.split()
        if "=>" in parts and len(parts) > parts.index("=>") + 1:
            p = parts[parts.index("=>") + 1]
            if p.startswith("/"):
                libs.append(p)
        elif parts and parts[0].startswith("/"):
            libs.append(parts[0])
    return libs


def make_image(bin_dir, root):
    copies, workdir = final_stage(os.path.join(ROOT, "deploy/Dockerfile"))
    for srcs, dest in copies:
        for s in srcs:
            src = build_source(s, bin_dir)
            if not os.path.exists(src):
                sys.exit(f"container_sim: COPY {s}: {src} does not exist (built?)")
            target = inside(root, dest)
            if dest.endswith("/"):
                os.makedirs(target, exist_ok=True)
                target = os.path.join(target, os.path.basename(src))
            if os.path.isdir(src):
                shutil.copytree(src, target, dirs_exist_ok=True)
            else:
                os.makedirs(os.path.dirname(target), exist_ok=True)
                shutil.copy2(src, target)
                copy_libs(root, src)
    # The base image's shell and coreutils the manifests' commands use.
    for tool in ["/bin/sh", "/bin/mkdir", "/bin/ls"]:
        copy_libs(root, os.path.realpath(tool))
        dest = inside(root, tool)
        if not os.path.exists(dest):
            os.makedirs(os.path.dirname(dest), exist_ok=True)
            shutil.copy2(os.path.realpath(tool), dest)
    os.makedirs(inside(root, workdir), exist_ok=True)
    return workdir


def run_job(doc, root, workdir, overrides, mounted, used):
    spec = doc["spec"]
    pod = spec["template"]["spec"]
    [container] = pod["containers"]
    claims = {v["name"]: v["persistentVolumeClaim"]["claimName"] for v in pod.get("volumes", [])}
    for m in container.get("volumeMounts", []):
        claim = claims[m["name"]]
        path = m["mountPath"]
        if mounted.get(path, claim) != claim:
            sys.exit(f"container_sim: {path} mounted from two claims")
        if path not in mounted:
            # The mount hides the image's files at `path`: an empty volume.
            target = inside(root, path)
            if os.path.exists(target):
                hidden = os.listdir(target)
                if hidden:
                    print(f"container_sim: the volume at {path} hides the image's {hidden}",
                          file=sys.stderr)
                shutil.rmtree(target)
            os.makedirs(target)
            mounted[path] = claim
    env = {"PATH": IMAGE_PATH, "HOME": "/root"}
    declared = set()
    for e in container.get("env", []):
        env[e["name"]] = str(e["value"])
        declared.add(e["name"])
    for name, value in overrides.items():
        if name in declared:
            env[name] = value
            used.add(name)
    argv = list(container.get("command", [])) + list(container.get("args", []))
    cwd = container.get("workingDir", workdir)
    indexed = spec.get("completionMode") == "Indexed"
    for i in range(int(spec.get("completions", 1))):
        if indexed:
            env["JOB_COMPLETION_INDEX"] = str(i)

        def enter():
            os.chroot(root)
            os.chdir(cwd)

        p = subprocess.run(argv, env=env, preexec_fn=enter, capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit(f"container_sim: job {doc['metadata']['name']} pod {i} exited "
                     f"{p.returncode}: {p.stderr.strip()}")


def main():
    if os.geteuid() != 0:
        os.execvp("unshare", ["unshare", "-r", sys.executable] + sys.argv)
    args = sys.argv[1:]
    if len(args) < 3:
        sys.exit(__doc__)
    bin_dir, work = os.path.abspath(args[0]), os.path.abspath(args[1])
    overrides, manifests, rest = {}, [], args[2:]
    while rest:
        a = rest.pop(0)
        if a == "--env":
            name, _, value = rest.pop(0).partition("=")
            overrides[name] = value
        else:
            manifests.append(a)
    root = os.path.join(work, "root")
    workdir = make_image(bin_dir, root)
    mounted, used = {}, set()
    for m in manifests:
        for doc in yaml.safe_load_all(open(m)):
            if doc and doc.get("kind") == "Job":
                run_job(doc, root, workdir, overrides, mounted, used)
    for name in set(overrides) - used:
        sys.exit(f"container_sim: --env {name}: no Job declares that variable")
    print(root)


if __name__ == "__main__":
    main()
