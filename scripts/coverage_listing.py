"""The listing step of scripts/sanitizer-coverage: reads the gcov counters of the module
libraries and prints the functions no test of the sanitizer selection executed.

Usage: coverage_listing.py SOURCE_DIR BUILD_DIR
Writes BUILD_DIR/uncovered.txt and BUILD_DIR/coverage-summary.json; exits 1 when the listing
differs from SOURCE_DIR/tests/sanitizers/uncovered.txt (new uncovered functions, or listed ones
that are now called)."""
import glob
import gzip
import json
import os
import re
import subprocess
import sys
import tempfile

MODULES = ["core", "sim", "drivers", "acquisition", "reconstruction", "meshing"]


def library_function(name):
    """External-linkage functions of the library: namespace scanmesh, not file-local helpers,
    lambdas or compiler-generated pieces."""
    if not name.startswith("scanmesh::"):
        return False
    for marker in ("(anonymous namespace)", "{lambda", "::detail::", "._omp_fn", "::{unnamed", "._"):
        if marker in name:
            return False
    return True


def short_name(demangled):
    """'scanmesh::f(int, double) const' -> 'scanmesh::f(int, double) const' without the return
    type gcov sometimes keeps in front."""
    return re.sub(r"\s+", " ", demangled).strip()


def read_counters(source_dir, build_dir):
    functions = {}  # (file, name) -> executed at least once
    files = set()
    for module in MODULES:
        objects = os.path.join(build_dir, module, "CMakeFiles")
        gcdas = glob.glob(os.path.join(objects, "**", "*.gcda"), recursive=True)
        gcnos = glob.glob(os.path.join(objects, "**", "*.gcno"), recursive=True)
        # A .gcno without .gcda: that translation unit never ran at all; gcov still lists its
        # functions (every count 0) from the notes file. One gcov run per object: objects of
        # sources with the same name would overwrite each other's output.
        inputs = gcdas + [g for g in gcnos if g[:-5] + ".gcda" not in gcdas]
        for obj in inputs:
            with tempfile.TemporaryDirectory() as out:
                subprocess.run(["gcov", "--json-format", "--demangled-names", obj], cwd=out,
                               check=False, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                for path in glob.glob(os.path.join(out, "*.gcov.json.gz")):
                    with gzip.open(path, "rt") as f:
                        data = json.load(f)
                    for entry in data.get("files", []):
                        file = os.path.normpath(os.path.join(data.get("current_working_directory", ""), entry["file"]))
                        rel = os.path.relpath(file, source_dir)
                        if not rel.startswith(module + "/src/"):
                            continue
                        files.add(rel)
                        # A function the compiler inlined into its callers keeps a call count of
                        # 0 even though its body ran: its lines' counts tell.
                        executed = {ln["line_number"] for ln in entry.get("lines", []) if ln["count"] > 0}
                        for fn in entry.get("functions", []):
                            name = short_name(fn.get("demangled_name", fn["name"]))
                            if not library_function(name):
                                continue
                            body_ran = any(line in executed for line in range(fn["start_line"], fn["end_line"] + 1))
                            key = (rel, name)
                            functions[key] = functions.get(key, False) or fn["execution_count"] > 0 or body_ran
    return functions, files


def read_allowlist(path):
    known = {}
    if not os.path.exists(path):
        return known
    reason = ""
    with open(path) as f:
        for line in f:
            line = line.rstrip("\n")
            if not line.strip():
                continue
            if line.startswith("#"):
                reason = line[1:].strip() or reason
                continue
            known[line.strip()] = reason
    return known


def main():
    source_dir, build_dir = sys.argv[1], sys.argv[2]
    functions, files = read_counters(source_dir, build_dir)
    if not functions:
        print("coverage_listing: no counters found under %s (build and run first)" % build_dir)
        return 2
    uncovered = sorted("%s  %s" % (f, n) for (f, n), hit in functions.items() if not hit)
    covered = sum(1 for hit in functions.values() if hit)
    with open(os.path.join(build_dir, "uncovered.txt"), "w") as f:
        f.write("\n".join(uncovered) + ("\n" if uncovered else ""))
    per_module = {}
    for (f, _), hit in functions.items():
        m = f.split("/")[0]
        c = per_module.setdefault(m, [0, 0])
        c[0] += hit
        c[1] += 1
    summary = {"functions": len(functions), "called": covered, "not_called": len(uncovered),
               "source_files": len(files),
               "per_module": {m: {"called": c[0], "functions": c[1]} for m, c in sorted(per_module.items())}}
    with open(os.path.join(build_dir, "coverage-summary.json"), "w") as f:
        json.dump(summary, f, indent=2)
    print("sanitizer-coverage: %d of %d library functions called by the sanitizer job's tests (%d files)"
          % (covered, len(functions), len(files)))
    for m, c in summary["per_module"].items():
        print("  %-15s %5d / %5d" % (m, c["called"], c["functions"]))
    known = read_allowlist(os.path.join(source_dir, "tests", "sanitizers", "uncovered.txt"))
    new = [u for u in uncovered if u not in known]
    gone = [k for k in known if k not in set(uncovered)]
    for u in new:
        print("NOT CALLED (not in tests/sanitizers/uncovered.txt): " + u)
    for k in gone:
        print("NOW CALLED (drop it from tests/sanitizers/uncovered.txt): " + k)
    print("listing: %s" % os.path.join(build_dir, "uncovered.txt"))
    return 1 if new or gone else 0


if __name__ == "__main__":
    sys.exit(main())
