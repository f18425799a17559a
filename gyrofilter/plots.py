"""Figures of filtered series (matplotlib, imported only when a figure is drawn)."""
from .extras import require


def pyplot():
    """matplotlib.pyplot with the file-only Agg backend, or MissingExtraError naming the extra."""
    require("matplotlib", "figures").use("Agg")
    return require("matplotlib.pyplot", "figures")


def plot_filtered(path, t_raw_s, raw_dps, t_filtered_s, filtered_dps, *, title="", truth=None):
    """Three panels (x, y, z): raw samples, filtered blocks and, if given, the true rate.

    ``truth`` is (t_s, rate_dps (N, 3)) or None. Written to ``path`` (PNG).
    """
    plt = pyplot()
    fig, axes = plt.subplots(3, 1, figsize=(10, 7), sharex=True)
    for a, ax in enumerate(axes):
        ax.plot(t_raw_s, raw_dps[:, a], lw=0.5, color="0.65", label="raw")
        if truth is not None:
            ax.plot(truth[0], truth[1][:, a], lw=1.2, color="tab:green", label="truth")
        ax.plot(t_filtered_s, filtered_dps[:, a], lw=1.0, color="tab:blue", label="filtered")
        ax.set_ylabel(f"{'xyz'[a]} (deg/s)")
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper right", ncol=3, fontsize="small")
    axes[-1].set_xlabel("time (s)")
    if title:
        axes[0].set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
