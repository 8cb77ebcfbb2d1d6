(A tool axis the head cannot reach within its travel: I0 J0.866025 K-0.5 leans the tool)
(120 deg from upright, beyond head_bc.json's B -110 to 110 deg.)
(engage moves head_overtravel.nc --dialect fanuc --machine data/machines/head_bc.json)
G21 G90 G94
G0 X0 Y0 Z50
G43.5 H1
G1 X10 I0 J0.5 K0.866025 F500
G1 X20 I0 J0.866025 K-0.5
G49
M30
