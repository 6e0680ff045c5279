"""rtcl_tools: rtcl's Python tools; commands/NAME.py is the command rtcl-NAME.

    commands     one module per command, main(argv) each: installed as rtcl-NAME by
                 pip install ./tools (tools/pyproject.toml) and make install, run
                 from a checkout as tools/NAME.py (a thin wrapper)
    files        the one atomic writer (text, figures, copies, all-or-nothing sets),
                 which never replaces a file tracked by git (--update-committed)
                 or one the tool reads (reading()); inputs opened without blocking
                 (open_input: no folder, FIFO or device); outputs checked first
    locations    where the tools find rtcl and the results folders
    requirements a missing numpy or matplotlib as one line, with its install command
    checkout     tools/NAME.py's Python: the running one, or another that has the
                 modules the tool needs (/usr/bin/python3 after make deps)
    interrupts   Ctrl-C, SIGTERM and SIGHUP as one line, temporary folders removed
    scene        the scene validator (docs/SCENE.md, mirroring host/scene/scene.c)
    runner       running rtcl: RtclFailed, Run, Settings, progress lines
    report       number formats, markdown tables, CSV, device folder names
    paper        the 2009 paper's figures and geometries
    flops        rtcl --flops files and parallel efficiency (numpy)
    histogram    Figure 7's histogram of a flops file, as results.json stores it
    plots        every matplotlib figure (matplotlib is imported only there)
    experiment, table1                      tools/experiments.py
    bench_plan, peak, bench_run, bench_report, bench_options, scaling   tools/bench.py
    usage        option checks and "PROGRAM: error: MESSAGE" reports
    povray_sdl, povray_run                  tools/povray.py
    genscene, vector                        tools/genscene.py
    images, ppm                             tools/imgdiff.py (and ppmdiff.py)

tools/NAME.py imports this package from its own folder, which Python puts first
on sys.path when it runs `python3 tools/NAME.py` from any directory, and calls
checkout.python_with(the modules it needs) before it imports its command.
"""
