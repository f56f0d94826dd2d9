"""emm run --list-sites as a user runs it, on the examples and on the
third-party mesh programs that are installed (each absent one is skipped
with a line):
- every rule the listing prints, used as printed (--tag RULE, --verbose),
  tags the block it was listed for: a block of the listed size, in whole
  records of the rule's stride (an axis rule with the rules of its mesh's
  other axis blocks, as a rule set needs x and y; a rule whose axis the
  listing says is a placeholder is not one to use as printed);
- the listing is the same byte for byte on 5 runs (ctmconv, and the smooth
  example under --capture valgrind, where the records come from accesses),
  and on 2 runs of every other program but Python's, whose allocations
  change from run to run (below);
- a stripped binary's frames (ctmconv's) are named MODULE+0xOFFSET, not
  after the nearest exported symbol.

    python3 sites.py EMM BINDIR WORKDIR VALGRIND(0|1)
"""
import os
import re
import shutil
import struct
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

EMM, BIN, WORK, VALGRIND = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4] == "1"
shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)
failures = []


def fail(msg):
    failures.append(msg)
    print("FAIL: " + msg, flush=True)


# Python seeds its string hashes at random, and with them when its dicts
# grow, from which call depth: the program itself allocates differently
# from run to run unless the seed is fixed. Even then, under load, its
# interned strings' dict grows at another depth in some runs (3 of 8): its
# listing is left out of the byte-identical checks.
ENV = dict(os.environ, PYTHONHASHSEED="0")


def run(args, stdin=None):
    with open(os.path.join(WORK, stdin)) if stdin else open(os.devnull) as f:
        p = subprocess.run(args, cwd=WORK, stdin=f, capture_output=True, text=True,
                           errors="replace", timeout=300, env=ENV)
    return p.returncode, p.stdout, p.stderr


# ---- inputs: a 12,000-face mesh (its arrays are listed: 64 KiB or more) ----
for f in ("m.off", "m.obj"):
    rc, _, err = run([EMM, "mesh", "gen", "--faces", "12000", "-o", f])
    if rc:
        sys.exit("cannot make %s: %s" % (f, err))
lines = open(os.path.join(WORK, "m.off")).read().split("\n")
nv, nf = map(int, lines[1].split()[:2])
verts = [tuple(map(float, l.split()[:3])) for l in lines[2:2 + nv]]
faces = [tuple(map(int, l.split()[1:4])) for l in lines[2 + nv:2 + nv + nf]]
with open(os.path.join(WORK, "m.stl"), "wb") as f:  # binary STL: 50-byte facets
    f.write(b"\0" * 80 + struct.pack("<I", nf))
    for a, b, c in faces:
        f.write(struct.pack("<3f", 0, 0, 1))
        for v in (a, b, c):
            f.write(struct.pack("<3f", *verts[v]))
        f.write(b"\0\0")
with open(os.path.join(WORK, "q.in"), "w") as f:  # qdelaunay: 3-d points (half: it is slow)
    f.write("3\n%d\n" % (nv // 2))
    for i, (x, y, _) in enumerate(verts[:nv // 2]):
        f.write("%r %r %r\n" % (x, y, (i * 7919 % 1000) / 1000.0))
with open(os.path.join(WORK, "p.node"), "w") as f:  # tetgen: the same points
    f.write("%d 3 0 0\n" % nv)
    for i, (x, y, _) in enumerate(verts):
        f.write("%d %r %r %r\n" % (i + 1, x, y, (i * 7919 % 1000) / 1000.0))
with open(os.path.join(WORK, "np.py"), "w") as f:
    f.write("import sys, meshio\n"
            "m = meshio.read(sys.argv[1])\n"
            "p, c = m.points, m.cells_dict['triangle']\n"
            "print(p[c].mean(axis=1).shape)\n")

ex = lambda name: os.path.join(BIN, name)
programs = [  # name, argv, stdin
    ("smooth", [ex("smooth"), "m.off", "1"], None),
    ("smooth_soa", [ex("smooth_soa"), "m.off", "1"], None),
    ("smooth_columns", [ex("smooth_columns"), "m.off", "1"], None),
    ("stl_normals", [ex("stl_normals"), "m.stl", "1"], None),
    ("flood_walk", [ex("flood_walk"), "m.obj", "200"], None),
    ("curve_tracing", [ex("curve_tracing"), "--short", "m.obj"], None),
    ("random_access", [ex("random_access"), "m.obj"], None),
    ("region_growing", [ex("region_growing"), "m.obj"], None),
    ("convert_once", [ex("convert_once"), "m.off", "out.stl"], None),
    ("ctmconv", ["ctmconv", "m.off", "out.stl"], None),
    ("admesh", ["admesh", "m.stl"], None),
    ("qdelaunay", ["qdelaunay", "Qt", "i"], "q.in"),
    ("tetgen", ["tetgen", "-Q", "p.node"], None),
    ("OpenMesh-Smoothing", ["OpenMesh-Smoothing", "1", "m.obj", "sm.obj"], None),
    ("OpenMesh-mconvert", ["OpenMesh-mconvert", "-i", "m.off", "-o", "mc.obj"], None),
    ("python3-meshio", ["/usr/bin/python3", "np.py", "m.off"], None),
]
present = []
for name, argv, stdin in programs:
    if not shutil.which(argv[0]):
        print("skipped %s: %s is not installed" % (name, argv[0]))
    elif name == "python3-meshio" and run([argv[0], "-c", "import meshio, numpy"])[0]:
        print("skipped %s: python3-meshio or python3-numpy is not installed" % name)
    else:
        present.append((name, argv, stdin))


def listing(argv, stdin, capture=None):
    # Under the fault capture unless valgrind is asked for: emm run's auto
    # lists an unmodified binary under valgrind, whose records come from
    # the accesses (tests/thirdparty uses it), at some 20 s for Python's.
    cap = ["--capture", capture or "fault"]
    rc, _, err = run([EMM, "run", "--list-sites"] + cap + ["--"] + argv, stdin)
    return "\n".join(l for l in err.split("\n") if l.startswith("emm: ")), err


# ---- the listings, and 5 runs for the byte-identical checks -------------
jobs = [(name, argv, stdin, None) for name, argv, stdin in present]
five = ("ctmconv",)
# (name, argv, stdin, capture, runs): every program twice under the fault
# capture (its first listing is one of them), five times those above, and
# the smooth example five times under valgrind.
same = [(n, a, s, None, 5 if n in five else 2) for n, a, s in present if n != "python3-meshio"]
if VALGRIND:
    same += [(n, a, s, "valgrind", 5) for n, a, s in present if n == "smooth"]
repeat = [(n, a, s, cap) for n, a, s, cap, k in same for _ in range(k - (cap is None))]
with ThreadPoolExecutor(2) as pool:
    lists = list(pool.map(lambda j: listing(j[1], j[2], j[3]), jobs + repeat))
listed = {j[0]: lists[i] for i, j in enumerate(jobs)}
for n, a, s, cap, k in same:
    runs = [lists[len(jobs) + i][0] for i, j in enumerate(repeat) if j[0] == n and j[3] == cap]
    if cap is None:
        runs.append(listed[n][0])
    under = " under valgrind" if cap else ""
    if len(set(runs)) != 1:
        fail("%s: the listing%s differs between %d runs" % (n, under, len(runs)))
    elif cap and "accesses by" not in runs[0]:
        fail("%s%s: no records from accesses:\n%s" % (n, under, runs[0]))
    else:
        print("%s%s: the same listing on %d runs" % (n, under, len(runs)))

# ---- a stripped binary's names --------------------------------------------
if "ctmconv" in listed:
    text = listed["ctmconv"][0]
    if "ctmconv+0x" not in text or "TiXml" in text:
        fail("ctmconv (stripped): frames not named ctmconv+0xOFFSET:\n" + text)
    else:
        print("ctmconv: frames named MODULE+0xOFFSET")
else:
    print("skipped the stripped-binary check: ctmconv is not installed")

# ---- OpenMesh's arrays named for what they are (issue 30) -----------------
for name in ("OpenMesh-Smoothing", "OpenMesh-mconvert"):
    if name not in listed:
        continue
    text = listed[name][0]
    blocks = text.split("\nemm: ")
    wrong = [b for b in blocks if "half-edge-like" in b and "rule: triangles:" in b]
    if wrong:
        fail("%s: a half-edge block listed with a triangles: rule:\n%s" % (name, wrong[0]))
    elif "--tag openmesh" not in text or "preset: OpenMesh's edges_" not in text:
        fail("%s: the listing does not name --tag openmesh and OpenMesh's edges_:\n%s" %
             (name, text))
    else:
        print("%s: OpenMesh's arrays named, the preset too, no triangles: for half-edges" % name)

# ---- every printed rule, used as printed ------------------------------------
site_re = re.compile(r"^emm: +\d+\. (.*): [\d,]+ blocks?, the largest ([\d,]+) bytes")
checks = []  # name, argv, stdin, rules text, [(largest, stride)]
for name, argv, stdin in present:
    text = listed[name][0]
    sites, axis = [], []
    cur = None
    for l in text.split("\n"):
        m = site_re.match(l)
        if m:
            cur = [m.group(1), int(m.group(2).replace(",", "")), None, False]
            sites.append(cur)
        elif cur and l.startswith("emm:      rule: ") and not l.startswith("emm:      rule: none"):
            cur[2] = l[len("emm:      rule: "):]
        elif cur and l.startswith("emm:      note: "):
            cur[3] = True  # x= is a placeholder: the axis is not known
    ruled = [s for s in sites if s[2]]
    print("%s: %d sites, %d with a rule" % (name, len(sites), len(ruled)))
    for site, largest, rule, placeholder in ruled:
        if placeholder:
            continue
        parts = rule.split(";")
        if len(parts) > 1:  # one call's x, y, z blocks: one each
            checks.append((name, argv, stdin, rule,
                           [(largest, 8 if "f64" in rule else 4)] * len(parts)))
            continue
        m = re.search(r"(^|,)([xyz])=\d+:(f32|f64)", rule)
        if m:
            axis.append((rule, largest, 8 if m.group(3) == "f64" else 4))
            continue
        stride = int(re.search(r"stride=(\d+)", rule).group(1))
        checks.append((name, argv, stdin, rule, [(largest, stride)]))
    if axis:
        checks.append((name, argv, stdin, ";".join(a[0] for a in axis),
                       [(a[1], a[2]) for a in axis]))

tag_re = re.compile(r"^emm: (?:tagged \w+ at \S+|moved \w+ from \S+ to \S+): (\d+) records of "
                    r"(\d+) bytes", re.M)


def check(c):
    name, argv, stdin, rules, want = c
    # The tagging alone: the sancov capture on a program not built for it
    # watches nothing (under the fault capture every access to the tagged
    # block faults: 10 s for numpy's).
    rc, _, err = run([EMM, "run", "--capture", "sancov", "--verbose", "--tag", rules, "--"] + argv,
                     stdin)
    got = [(int(n), int(s)) for n, s in tag_re.findall(err)]
    missing = [(largest, stride) for largest, stride in want
               if (largest // stride, stride) not in got]
    return c, missing, err


with ThreadPoolExecutor(2) as pool:
    for (name, _, _, rules, want), missing, err in pool.map(check, checks):
        if missing:
            fail("%s: --tag '%s' did not tag the listed block%s %s:\n%s" %
                 (name, rules, "s" if len(missing) > 1 else "",
                  ", ".join("of %d bytes" % m[0] for m in missing),
                  "\n".join(l for l in err.split("\n") if l.startswith("emm:"))[:3000]))
        else:
            print("%s: %s tags the listed block%s" % (name, rules, "s" if len(want) > 1 else ""))

if failures:
    sys.exit(1)
print("sites: ok (%d programs, %d rule sets)" % (len(present), len(checks)))
