; grbl-style program: no spaces, lower case, semicolon comments
g21g90
m3s12000
g0x5y5z3
g1z-0.5f200
g1x25y5f800 ; bottom edge
g1x25y25
g2x15y35i-10j0 ; round top right
g1x5y25
g1x5y5
g0z3
g4p0.5
g0x0y0
m5
m2
