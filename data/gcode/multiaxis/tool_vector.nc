%
O1005 (TOOL AXIS AS I J K)
(Fanuc's tool centre point control type 2, G43.5: X, Y, Z the tip on the part, I, J, K the)
(tool's axis at each line's end; the controller turns the head's B and C to it.)
(engage schedule tool_vector.nc --dialect fanuc --machine data/machines/head_bc.json)
(  --tool ball --diameter 6mm --stock box:0,0,-10,40,20,0 --target-mrr 800)
(Line 16: a 6 mm ball leaning 30 deg towards +Y, B30 C-90, its centre 2 mm above the top:)
(by hand, the segment of r 3 and depth 1, 9 acos[2/3] - 2 sqrt[5] = 3.09748 mm^2, over)
(the 40 mm box: 123.899 mm^3. Line 20: a second groove, the tool turning upright as it goes.)
(Line 24: the tool turning 30 deg about its standing tip, 1 mm into the top.)
G21 G90 G94 G17 G40 G49 G80
G0 X-5 Y8.5 Z20
G43.5 H1
G0 I0 J0.5 K0.866025404
G0 Z-0.598076211
G1 X45 F300
G0 Z20
G0 X-5 Y3.5
G0 Z-0.598076211
G1 X45 Y5 Z-1 K1
G0 Z20
G0 X20 Y16
G1 Z-1 F300
G1 J0.5 K0.866025404
G0 Z20
G49
M30
%
