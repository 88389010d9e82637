"""The requirement lists the set-up hands to pip, built from the files beside
this one; standard library only, so any Python 3 runs it.

    python3 requirements.py merge FILE... [--floor FLOOR]
        The pins of the FILEs, with those FLOOR pins in place of theirs
        (every line of FLOOR naming a package replaces that package's lines).
    python3 requirements.py select NAMES FILE...
        The pins of the FILEs for the packages that NAMES lists, one a line.
    python3 requirements.py installed
        ``name==version`` of every distribution this interpreter can import,
        as pip constraints: on a ROS install, what the distro provides.
    python3 requirements.py report REPORT
        ``name version`` of what a ``pip install --report REPORT`` installed.
"""

import argparse
import importlib.metadata
import json
import re
import sys

# PEP 440 public versions with an optional local part: the versions a
# constraint can pin.  Some distro packages carry others ("1.2.3-1ubuntu1").
_VERSION = re.compile(r"^\d+(\.\d+)*((a|b|rc)\d+)?(\.post\d+)?(\.dev\d+)?(\+[a-z0-9.]+)?$",
                      re.IGNORECASE)


def normalized(name):
    """A distribution's name as pip compares it (PEP 503)."""
    return re.sub(r"[-_.]+", "-", name).lower()


def pins(path):
    """``(normalized name, line)`` for each requirement line of a file."""
    with open(path, encoding="utf-8") as lines:
        for line in lines:
            line = line.split("#", 1)[0].strip()
            if line:
                yield normalized(re.split(r"[\s=<>!~;\[]", line, maxsplit=1)[0]), line


def names(path):
    """The normalized names a requirements file lists."""
    return [name for name, _ in pins(path)]


def merge(files, floor=None):
    """The requirement lines of ``files``, ``floor``'s lines replacing those
    of the packages it names, in the files' order."""
    replaced = {}
    for name, line in pins(floor) if floor else ():
        replaced.setdefault(name, []).append(line)
    lines, seen = [], set()
    for path in files:
        for name, line in pins(path):
            if name in seen and name not in replaced:
                raise SystemExit(f"{path}: {name} is pinned twice")
            seen.add(name)
            lines.append(line if name not in replaced else None)
    unused = sorted(set(replaced) - seen)
    if unused:
        raise SystemExit(f"{floor}: {', '.join(unused)} pinned by none of {', '.join(files)}")
    return [line for line in lines if line] + [line for name in replaced
                                               for line in replaced[name]]


def select(names_file, files):
    """The pin lines of ``files`` for the packages ``names_file`` lists."""
    wanted = names(names_file)
    pinned = {name: line for path in files for name, line in pins(path)}
    missing = [name for name in wanted if name not in pinned]
    if missing:
        raise SystemExit(f"{names_file}: {', '.join(missing)} pinned in none of "
                         f"{', '.join(files)}")
    return [pinned[name] for name in wanted]


def installed():
    """A ``name==version`` constraint for every importable distribution
    whose version pip can pin."""
    found = {}
    for distribution in importlib.metadata.distributions():
        name, version = distribution.metadata["Name"], distribution.version
        if name and version and _VERSION.match(version):
            found.setdefault(normalized(name), f"{name}=={version}")
    return sorted(found.values(), key=str.lower)


def report(path):
    """``name version`` of each distribution a pip installation report
    lists as installed."""
    with open(path, encoding="utf-8") as file:
        document = json.load(file)
    return sorted((f"{item['metadata']['name']} {item['metadata']['version']}"
                   for item in document.get("install", ())), key=str.lower)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    verbs = parser.add_subparsers(dest="verb", required=True)
    merging = verbs.add_parser("merge")
    merging.add_argument("files", nargs="+")
    merging.add_argument("--floor")
    selecting = verbs.add_parser("select")
    selecting.add_argument("names")
    selecting.add_argument("files", nargs="+")
    verbs.add_parser("installed")
    reporting = verbs.add_parser("report")
    reporting.add_argument("path")
    args = parser.parse_args(argv)
    if args.verb == "merge":
        lines = merge(args.files, args.floor)
    elif args.verb == "select":
        lines = select(args.names, args.files)
    elif args.verb == "installed":
        lines = installed()
    else:
        lines = report(args.path)
    sys.stdout.write("".join(f"{line}\n" for line in lines))


if __name__ == "__main__":
    main()
