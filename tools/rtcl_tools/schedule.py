"""rtcl --schedule-map files: which work-group and work-item traced each pixel, and when.

`rtcl --schedule-map FILE.npy` writes dtype '<u4', shape (height, width, 3), row 0
at the top: [..., 0] the work-group, [..., 1] the work-item in the group, [..., 2]
the ticket, the pixel's place in the order pixels were started (docs/RENDERING.md,
"The schedule map").  A pixel never started has the group UNSTARTED_GROUP.
"""

import pathlib

import numpy as np

from .flops import read_npy

SCHEDULE_DTYPE = np.dtype("<u4")
UNSTARTED_GROUP = 0xFFFFFFFF


class ScheduleMapError(ValueError):
    """A schedule map that cannot be read; the message names the file."""


def load_map(path):
    """Returns the (height, width, 3) uint32 array of the schedule map at path;
    raises ScheduleMapError naming what is wrong."""
    path = pathlib.Path(path)
    array = read_npy(path, ScheduleMapError)
    if array.dtype != SCHEDULE_DTYPE or array.ndim != 3 or array.shape[2] != 3 \
            or array.size == 0:
        raise ScheduleMapError(f"{path}: not a schedule map (dtype {array.dtype}, shape "
                               f"{array.shape}; rtcl --schedule-map writes uint32, "
                               "height x width x 3)")
    return array


def started(schedule):
    """Returns the (height, width) booleans: True where a work-item started the pixel."""
    return schedule[..., 0] != UNSTARTED_GROUP


def order_started(schedule):
    """Returns each started pixel's place in the order pixels were started as a
    share of the started pixels, 0 for the first and 1 for the last (float64,
    height x width), NaN where no work-item started the pixel.  Ranks of the
    tickets, so the shares stay in 0..1 even if the tickets leave gaps."""
    shown = started(schedule)
    share = np.full(shown.shape, np.nan)
    tickets = schedule[..., 2][shown]
    ranks = np.empty(tickets.size, dtype=np.float64)
    ranks[np.argsort(tickets, kind="stable")] = np.arange(tickets.size)
    share[shown] = ranks / max(tickets.size - 1, 1)
    return share
