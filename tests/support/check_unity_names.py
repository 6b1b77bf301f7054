#!/usr/bin/env python3
"""check_unity_names.py TESTS_DIR: the names each test file defines at file scope (helpers, constants,
types in its anonymous namespace) must differ from every other file's of the same test program; and the
names each library source (*/src/**/*.cpp beside TESTS_DIR) defines in its anonymous namespace must
differ from every other library source's.

The test programs compile in unity batches of eight (tests/CMakeLists.txt): two files of one batch that
define the same name do not compile, and two that overload one can silently call each other's. Which
files share a batch depends on the order of the sources, so a new file can bring two old ones together:
this check finds every such pair now, whatever the batches. It reads the programs' sources from
tests/**/CMakeLists.txt (ctsurg_add_tests(<program> ... SOURCES ...)) and the names from the lines that
start a declaration at column 0 (a function, a variable, a struct, class or enum); using-declarations
and aliases are left out (redeclaring one alias to the same type is allowed). Exit 1, naming each name and
its files, when two files of a program share one. The libraries compile in unity batches too (cmake/
CtsurgUnityBuild.cmake), and the fuzz build batches files of several libraries together
(tests/fuzz/CMakeLists.txt), so a library source's file-local names are checked against the whole tree.
"""
import collections
import glob
import os
import re
import sys

root = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
programs = collections.defaultdict(list)
for cmake in glob.glob(os.path.join(root, "**", "CMakeLists.txt"), recursive=True):
    folder = os.path.dirname(cmake)
    for m in re.finditer(r"ctsurg_add_tests\((\w+)(.*?)\)\s*$", open(cmake).read(), re.S | re.M):
        sources = re.search(r"SOURCES(.*?)(?:\bLIBS\b|\bTOOLS\b|$)", m.group(2), re.S)
        if sources:
            programs[m.group(1)] += [os.path.join(folder, f) for f in sources.group(1).split() if f.endswith(".cpp")]

declaration = re.compile(r"^(?:static\s+|inline\s+|constexpr\s+|const\s+)*(?:[\w:<>,]+(?:\s*[*&])?\s+)+?(\w+)\s*(?:\(|=|\{|\[|;)")
type_name = re.compile(r"^(?:struct|class|enum(?:\s+class)?)\s+(\w+)")
shared = 0
for program, files in sorted(programs.items()):
    owners = collections.defaultdict(set)
    for path in files:
        for line in open(path, encoding="utf-8"):
            if not line or line[0] in " \t#/}" or line.startswith(("TEST", "namespace", "using", "template", "extern")):
                continue
            m = type_name.match(line) or declaration.match(line)
            if m and m.group(1) not in ("main", "operator"):
                owners[m.group(1)].add(os.path.relpath(path, root))
    for name, paths in sorted(owners.items()):
        if len(paths) > 1:
            shared += 1
            print(f"{program}: '{name}' is defined at file scope in {', '.join(sorted(paths))}: give each file its own name")
# Library sources: the names in each file's anonymous namespace (from "namespace {" to its closing
# "}  // namespace" at column 0), against every other library source.
project = os.path.dirname(os.path.abspath(root))
local_owners = collections.defaultdict(set)
for path in glob.glob(os.path.join(project, "*", "**", "src", "**", "*.cpp"), recursive=True):
    relative = os.path.relpath(path, project)
    if relative.split(os.sep)[0].startswith("build") or relative.startswith("tests" + os.sep):
        continue
    anonymous = False
    for line in open(path, encoding="utf-8", errors="replace"):
        if line.startswith("namespace {"):
            anonymous = True
        elif anonymous and line.startswith("}  // namespace"):
            anonymous = False
        elif anonymous and line and line[0] not in " \t#/}" and not line.startswith(("namespace", "using", "template", "extern")):
            m = type_name.match(line) or declaration.match(line)
            if m and m.group(1) not in ("main", "operator"):
                local_owners[m.group(1)].add(relative)
for name, paths in sorted(local_owners.items()):
    if len(paths) > 1:
        shared += 1
        print(f"libraries: '{name}' is defined in the anonymous namespace of {', '.join(sorted(paths))}: give each file its own name")
if not programs:
    print(f"no test program found under {root}")
    sys.exit(1)
if shared:
    sys.exit(1)
print(f"{sum(len(f) for f in programs.values())} test files of {len(programs)} programs and the library sources: every file-scope name is "
      "its file's own")
