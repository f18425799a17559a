"""Figures of filtered series (matplotlib, imported only when a figure is drawn)."""
import os

from .errors import SettingsError, naming_file
from .extras import require
from .units import AXES


def pyplot():
    """matplotlib.pyplot with the file-only Agg backend, or MissingExtraError naming the extra."""
    require("matplotlib", "figures").use("Agg")
    return require("matplotlib.pyplot", "figures")


def plain_text(text):
    """``text`` (a file name, a title holding one) as matplotlib shows it unchanged: each ``$``
    escaped (``\\$``), so that no pair of them reads as mathtext (a name ``x$\\foo$.csv`` failed
    to draw with "Unknown symbol", ``z$x$.csv`` showed "zx.csv"). The one rule of the text a
    figure takes from the user."""
    return str(text).replace("$", r"\$")


def save_figure(fig, path, dpi=110):
    """Write the matplotlib figure ``fig`` to ``path`` and close it. A write error that names no
    file (a full disk or a file size limit met inside the image writer, which then removes the file
    it made) names ``path`` (:func:`gyrofilter.errors.naming_file`)."""
    plt = pyplot()
    try:
        with naming_file(path):
            fig.savefig(path, dpi=dpi)
    finally:
        plt.close(fig)


def check_figure_path(path, option="--plot"):
    """Refuse, before any work, a figure file ``path`` whose extension matplotlib cannot write
    (SettingsError naming ``option``, the command-line option that gave it, and the formats it
    can); matplotlib missing is said here too."""
    pyplot()
    from matplotlib.backend_bases import FigureCanvasBase

    formats = FigureCanvasBase.get_supported_filetypes()
    ext = os.path.splitext(path)[1].lstrip(".").lower()
    if ext not in formats:
        raise SettingsError(f"{option} {path}: matplotlib cannot write {'.' + ext if ext else 'a file without an extension'}; "
                            f"use one of {', '.join('.' + f for f in sorted(formats))}")


def plot_filtered(path, raw, filtered, *, title=""):
    """Three panels (x, y, z): raw samples and filtered rows, each given as a min/max
    :class:`~gyrofilter.streamstats.Envelope` (a band per bucket; a line while a bucket is one
    sample), so that a day of data draws in bounded memory; time in s, rates in deg/s, headed
    ``title``. Written to ``path`` (PNG)."""
    plt = pyplot()
    fig, axes = plt.subplots(3, 1, figsize=(10, 7), sharex=True)
    for a, ax in enumerate(axes):
        for env, color, width, label in ((raw, "0.65", 0.5, "raw"), (filtered, "tab:blue", 1.0, "filtered")):
            if env.bucket == 1:
                ax.plot(env.t_s, env.low[:, a], lw=width, color=color, label=label)
            else:
                ax.fill_between(env.t_s, env.low[:, a], env.high[:, a], step="post", lw=0, color=color,
                                alpha=0.8, label=f"{label} (min..max per {env.bucket} samples)")
        ax.set_ylabel(f"{AXES[a]} (deg/s)")
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper right", ncol=2, fontsize="small")
    axes[-1].set_xlabel("time (s)")
    if title:
        axes[0].set_title(plain_text(title))
    fig.tight_layout()
    save_figure(fig, path)
