"""Checks host/'s layering rule (docs/STYLE.md, "Layers").

Each folder of host/ may include the headers of, and call, only itself and the
folders its row of the table in docs/STYLE.md names. The table is read from
STYLE.md, so the rule and its check cannot drift apart. Checked:

- every source file of host/ lies in a folder of the table;
- every include of one of rtcl's own headers names its folder
  ("render/launch.h", never "launch.h") and points to an allowed folder;
- with --objects BUILD, every function or variable an object uses from
  another of rtcl's objects is defined in an allowed folder (calls that an
  include check cannot see: a declaration written by hand).

Exceptions are rows of the table under "Exceptions" in the same section,
each with its reason; there are none today. Prints one line per violation
and exits with 1 if there is any.

    python3 tools/build/layers.py [--root DIR] [--objects BUILD]
"""
import argparse
import os
import re
import subprocess
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
SOURCE_ENDINGS = ('.c', '.h', '.cpp')


def read_rules(style_path):
    """The folders in order, what each may use, and the allowed exceptions
    (file, target) from STYLE.md's "Layers" section."""
    with open(style_path, encoding='utf-8') as f:
        text = f.read()
    start = text.find('\n## Layers')
    if start < 0:
        sys.exit(f'{style_path}: no "## Layers" section')
    end = text.find('\n## ', start + 1)
    section = text[start:end if end > 0 else len(text)]
    uses, order, exceptions = {}, [], set()
    in_exceptions = False
    for line in section.splitlines():
        if line.startswith('### Exceptions'):
            in_exceptions = True
            continue
        cells = [c.strip() for c in line.strip().strip('|').split('|')]
        if not line.startswith('|') or len(cells) < 3 or set(cells[0]) <= set('-: '):
            continue
        if in_exceptions:
            if cells[0] != 'file':
                exceptions.add((cells[0].strip('`'), cells[1].strip('`')))
            continue
        folder = cells[0].strip('`')
        if folder == 'folder':
            continue
        allowed = cells[2]
        uses[folder] = set() if allowed in ('', '-', '—') else {
            w.strip('`,') for w in allowed.split() if w.strip('`,')}
        order.append(folder)
    if not uses:
        sys.exit(f'{style_path}: the "Layers" table has no rows')
    for folder, allowed in uses.items():
        unknown = allowed - set(uses)
        if unknown:
            sys.exit(f'{style_path}: {folder} may use unknown folders {sorted(unknown)}')
    return order, uses, exceptions


def host_sources(host):
    for folder, _, files in os.walk(host):
        for name in sorted(files):
            if name.endswith(SOURCE_ENDINGS):
                yield os.path.relpath(os.path.join(folder, name), host)


def check_includes(host, uses, exceptions):
    problems = []
    headers = {p for p in host_sources(host) if p.endswith('.h')}
    by_name = {}
    for h in headers:
        by_name.setdefault(os.path.basename(h), []).append(h)
    for path in host_sources(host):
        folder = path.split('/')[0] if '/' in path else ''
        if folder not in uses:
            problems.append(f'host/{path}: not in a folder of the Layers table '
                            f'(docs/STYLE.md)')
            continue
        with open(os.path.join(host, path), encoding='utf-8') as f:
            text = f.read()
        for target in INCLUDE.findall(text):
            if target in headers:
                to = target.split('/')[0]
                if to != folder and to not in uses[folder] and \
                        (path, target) not in exceptions:
                    problems.append(f'host/{path}: includes {target}: {folder}/ may use '
                                    f'{", ".join(sorted(uses[folder])) or "no other folder"}')
            elif os.path.basename(target) in by_name and '/' not in target:
                problems.append(f'host/{path}: includes "{target}": write it with its folder, '
                                f'"{by_name[target][0]}"')
            elif '/' in target and target.split('/')[0] in uses:
                problems.append(f'host/{path}: includes "{target}", which does not exist')
    return problems


def symbols(obj):
    """(defined, undefined) external symbols of an object file."""
    out = subprocess.run(['nm', '-P', obj], capture_output=True, text=True, check=True).stdout
    defined, undefined = set(), set()
    for line in out.splitlines():
        parts = line.split()
        if len(parts) < 2:
            continue
        name, kind = parts[0], parts[1]
        if kind == 'U':
            undefined.add(name)
        elif kind in 'TDBRCVWGS':  # external definitions only
            defined.add(name)
    return defined, undefined


def check_objects(build, uses, exceptions):
    """Calls between folders, from the objects in build/FOLDER/."""
    problems = []
    owner, needs = {}, {}
    for folder in uses:
        directory = os.path.join(build, folder)
        if not os.path.isdir(directory):
            continue
        for name in sorted(os.listdir(directory)):
            if not name.endswith('.o') or name.endswith('.pic.o'):
                continue
            obj = os.path.join(directory, name)
            defined, undefined = symbols(obj)
            for s in defined:
                owner.setdefault(s, (folder, name))
            needs[(folder, name)] = undefined
    for (folder, name), undefined in sorted(needs.items()):
        for s in sorted(undefined):
            if s not in owner:
                continue
            to, to_name = owner[s]
            if to == folder or to in uses[folder]:
                continue
            source = f'{folder}/{name[:-2]}'
            if (source, f'{to}/{to_name[:-2]}') in exceptions:
                continue
            problems.append(f'{build}/{folder}/{name}: calls {s} of {to}/{to_name[:-2]}: '
                            f'{folder}/ may use {", ".join(sorted(uses[folder])) or "no other folder"}')
    return problems


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--root', default='.', help='the checkout (default: here)')
    parser.add_argument('--objects', metavar='BUILD',
                        help='also check the calls between the objects of this build folder')
    args = parser.parse_args()
    order, uses, exceptions = read_rules(os.path.join(args.root, 'docs', 'STYLE.md'))
    problems = check_includes(os.path.join(args.root, 'host'), uses, exceptions)
    if args.objects:
        problems += check_objects(args.objects, uses, exceptions)
    for p in problems:
        print(p)
    what = 'includes and calls' if args.objects else 'includes'
    print(f'layers: {len(problems)} violation{"" if len(problems) == 1 else "s"} of the '
          f'layering rule ({what}; {len(order)} folders; {len(exceptions)} exception'
          f'{"" if len(exceptions) == 1 else "s"} in docs/STYLE.md)')
    return 1 if problems else 0


if __name__ == '__main__':
    sys.exit(main())
