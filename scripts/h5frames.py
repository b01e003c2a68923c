"""Shared by the figure scripts that read a run's frames (plot_a6.py,
plot_a7.py): the particle positions of every frame of DIR/bfemp.h5, and the
command line OUT.png LABEL=DIR [LABEL=DIR ...] [--title TEXT] (DIR may be
DIR1+DIR2: a run continued in another directory)."""
import h5py


def particle_frames(run_dir):
    """[(time, positions (n x dim))] of every frame of run_dir/bfemp.h5, in order.
    run_dir may chain runs as DIR1+DIR2+...: a run and its continuations
    written elsewhere (`bfemp restart DIR1 --output DIR2`); each later run
    adds its frames after the time of the last one before it."""
    frames = []
    for d in run_dir.split("+"):
        f = h5py.File(d + "/bfemp.h5", "r")
        names = sorted(k for k in f if k.startswith("frame_"))
        last = frames[-1][0] if frames else -float("inf")
        frames += [(f[k].attrs["time"], f[k]["particle_positions"][:]) for k in names
                   if f[k].attrs["time"] > last + 1e-9]
    return frames


def parse_args(argv):
    """(out, [(label, dir)], title) from OUT.png LABEL=DIR ... [--title TEXT]."""
    args = list(argv)
    title = ""
    if "--title" in args:
        k = args.index("--title")
        title = args[k + 1]
        del args[k:k + 2]
    return args[0], [a.split("=", 1) for a in args[1:]], title
