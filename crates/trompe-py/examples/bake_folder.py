"""Bakes every mesh under a folder to octahedral atlases, with a progress bar.

    python crates/trompe-py/examples/bake_folder.py assets/ out/atlases --frames 8 --resolution 512

Folders are walked for .obj, .ply, .gltf and .glb files and mirrored under the output folder; a
second run with --skip-existing bakes only what changed. Uses tqdm's bar when tqdm is
installed, a bar of its own otherwise.
"""

import argparse
import sys
import time

import trompe


def text_bar():
    start = time.monotonic()

    def show(done, total, path):
        width = 30
        filled = width * done // max(total, 1)
        elapsed = time.monotonic() - start
        sys.stderr.write(
            f"\r[{'=' * filled}{' ' * (width - filled)}] {done}/{total} {elapsed:6.1f} s  {path[-40:]:<40}"
        )
        if done == total:
            sys.stderr.write("\n")
        sys.stderr.flush()

    return show, lambda: None


def tqdm_bar():
    from tqdm import tqdm

    bar = tqdm(unit="mesh")

    def show(done, total, path):
        bar.total = total
        bar.set_postfix_str(path[-40:])
        bar.update(1)

    return show, bar.close


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("inputs", nargs="+", help="meshes and folders")
    parser.add_argument("output", help="the output folder")
    parser.add_argument("--frames", type=int, default=16)
    parser.add_argument("--resolution", type=int, default=2048)
    parser.add_argument("--glb", action="store_true")
    parser.add_argument("--skip-existing", action="store_true")
    args = parser.parse_args()
    try:
        show, close = tqdm_bar()
    except ImportError:
        show, close = text_bar()
    try:
        manifest = trompe.bake_octahedral(
            args.inputs,
            args.output,
            frames=args.frames,
            resolution=args.resolution,
            glb=args.glb,
            skip_existing=args.skip_existing,
            progress=show,
        )
    except trompe.TrompeError as e:
        sys.exit(f"error: {e}")
    finally:
        close()
    failed = [e for e in manifest["entries"] if e["error"]]
    for e in failed:
        print(f"skipped {e['input']}: {e['error']}", file=sys.stderr)
    baked = len(manifest["entries"]) - len(failed)
    print(f"{baked} of {len(manifest['entries'])} meshes baked into {args.output}")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
