#!/usr/bin/env python3
"""Random LinuxCNC lathe-cycle programs (G70, G71, G71.1, G71.2, G72, G72.1, G72.2) for a
differential test of engage's reader against LinuxCNC's rs274:

  scripts/random_lathe_cycles.py FIRST_SEED LAST_SEED OUT_DIR
  scripts/compare_linuxcnc.py OUT_DIR/*.ngc

Each program: a profile of lines (some with A fillets or C chamfers), G3/G2 quarter arcs (IJK
or R form) and sometimes a pocket, mirrored at random in X (turning / boring) and Z, cut by one
random cycle with random D, I, R (or G70's D, E, P), in radius or diameter mode, in G54 or
G55 with an offset. The same seeds give the same programs.
"""
import random, sys, re, os
def prog(seed):
    r = random.Random(seed)
    L = []
    L.append("G18 G21 G90 F%d" % r.choice([100,250]))
    if r.random()<0.2: L.append("G7")
    if r.random()<0.2: L.append("G55\nG10 L2 P2 X%.1f Z%.1f" % (r.uniform(-5,5), r.uniform(-5,5)))
    L.append("G0 X30 Z10")
    # profile: turning profile decreasing X towards axis? build monotone profile
    # start at small x near z=0, go -z with x increasing (outer turning)
    x = r.choice([0, 2, 4]); z = 0.0
    sub = ["O100 SUB", " G1 X%.3f Z%.3f" % (x, z)]
    n = r.randint(2,6)
    pocket = r.random() < 0.4
    for i in range(n):
        kind = r.random()
        dz = -r.uniform(2,6)
        if kind < 0.45:
            dx = r.uniform(0,4)
            if pocket and i == n//2: dx = -r.uniform(1,2)
            x += dx; z += dz
            extra = ""
            if r.random() < 0.2 and i < n-1: extra = " A%.2f" % r.uniform(0.3,0.8)
            elif r.random() < 0.2 and i < n-1: extra = " C%.2f" % r.uniform(0.3,0.8)
            sub.append(" G1 X%.3f Z%.3f%s" % (x, z, extra))
        elif kind < 0.6:
            x += 0; z += dz
            sub.append(" G1 Z%.3f" % z)
        else:
            # quarter-ish arc: convex or concave
            rad = r.uniform(2,4)
            if r.random()<0.5:
                # G3 convex shoulder: centre at (x, z - rad)?  arc from (x,z) to (x+rad, z-rad), centre (x, z-rad)
                g = "G3" if True else "G2"
                cx, cz = x, z - rad
                nx, nz = x + rad, z - rad
                if r.random()<0.5:
                    sub.append(" G3 X%.3f Z%.3f I%.3f K%.3f" % (nx, nz, cx-x, cz-z))
                else:
                    sub.append(" G3 X%.3f Z%.3f R%.3f" % (nx, nz, rad))
            else:
                # G2 concave: from (x,z) to (x+rad, z-rad) centre (x+rad, z)
                cx, cz = x + rad, z
                nx, nz = x + rad, z - rad
                if r.random()<0.5:
                    sub.append(" G2 X%.3f Z%.3f I%.3f K%.3f" % (nx, nz, cx-x, cz-z))
                else:
                    sub.append(" G2 X%.3f Z%.3f R%.3f" % (nx, nz, rad))
            x, z = nx, nz
    sub.append("O100 ENDSUB")
    mx = r.choice([1,-1]); mz = r.choice([1,-1])
    def flip(line):
        def rep(m):
            v=float(m.group(2)); k=m.group(1)
            if k in 'XI': v*=mx
            if k in 'ZK': v*=mz
            return "%s%.3f"%(k,v)
        line = re.sub(r'([XZIK])(-?[0-9.]+)', rep, line)
        if mx*mz < 0: line = line.replace('G2 ','G@ ').replace('G3 ','G2 ').replace('G@ ','G3 ')
        return line
    sub = [flip(l) for l in sub]
    L += sub
    X = (x + r.uniform(1,3))*mx; Z = r.uniform(1,3)*mz
    cyc = r.choice(["G71","G71.1","G71.2","G70","G72","G72.1","G72.2"])
    D = r.choice([0, 0.2, 0.5]); I = r.choice([0.5, 1, 1.5]); R = r.choice([0.3, 0.5])
    if cyc == "G70":
        L.append("G70 Q100 X%.3f Z%.3f D%.2f E%.2f P%d" % (X, Z, r.choice([0,0.5,1]), r.choice([0,0.1]), r.randint(1,3)))
    else:
        uw = ""
        pass
        L.append("%s Q100 X%.3f Z%.3f D%.2f I%.2f R%.2f%s" % (cyc, X, Z, D, I, R, uw))
    L.append("G1 X40 Z20")
    L.append("M2")
    return "\n".join(L) + "\n"
os.makedirs(sys.argv[3], exist_ok=True)
for s in range(int(sys.argv[1]), int(sys.argv[2])):
    open(os.path.join(sys.argv[3], "p%04d.ngc" % s), "w").write(prog(s))
