"""The 2009 paper's experiment: its figures, and the geometries that reproduce it."""

# The paper's Table 1 and speedups (Figure 6); times in seconds.
PAPER = {
    "serial": {"workgroup": "-", "threads": "-", "time_s": 90.56, "gflops": None,
               "efficiency": None, "speedup": 1.0},
    "naive": {"workgroup": "16x10", "threads": "2000x2000", "time_s": 1.75,
              "gflops": 10.91, "efficiency": 0.1120, "speedup": 52.0},
    "cyclic": {"workgroup": "8x8", "threads": "200x200", "time_s": 0.43,
               "gflops": 44.10, "efficiency": 0.7744, "speedup": 211.0},
    "dynamic": {"workgroup": "8x8", "threads": "80x80", "time_s": 0.44,
                "gflops": 43.37, "efficiency": 0.8536, "speedup": 206.0},
}
PARALLEL_KERNELS = ("naive", "cyclic", "dynamic", "persistent", "wavefront")
# The kernels that take --groups (persistent work-groups).
GROUP_KERNELS = ("cyclic", "dynamic", "persistent")
# The paper's geometries: kernel -> (work-group, groups or None); for persistent
# and wavefront, which the paper did not run, the nearest: dynamic's geometry,
# and the 8x8 work-group of the primary-ray launch.
PAPER_GEOMETRY = {"naive": ("16x10", None), "cyclic": ("8x8", "25x25"),
                  "dynamic": ("8x8", "10x10"), "persistent": ("8x8", "10x10"),
                  "wavefront": ("8x8", None)}
# --batch for the kernels that take it (pixels per fetch).
PAPER_BATCH = {"persistent": 1}

# How tools/experiments.py sweeps beyond the paper's geometries.
SWEEP_WORKGROUPS = ("8x8", "16x8", "16x16", "32x4", "32x8")
SWEEP_GROUP_SCALES = (1.5, 2.0)         # per dimension: 2.25x and 4x the groups
QUICK_WORKGROUPS = ("8x8", "16x8")
QUICK_GROUP_SCALES = (2.0,)
QUICK_SIZE = "400x400"
SWEEP_REPEAT = 3
DEFAULT_REPEAT = 5
