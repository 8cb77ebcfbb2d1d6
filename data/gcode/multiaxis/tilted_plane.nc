%
O1002 (TILTED WORK PLANE)
(The slot of tilted_slot.ngc written as a Fanuc post writes 3+2 work: on a tilted work)
(plane, G68.2, whose Z leans 30 deg towards +Y; G53.1 turns the trunnion's A to it; the)
(plane's X, Y, Z are the tip's, Rx[30 deg] times the part's. On the trunnion without the)
(controller's tip control:)
(engage simulate tilted_plane.nc --machine data/machines/table_ac.json --tool ball)
(  --diameter 6mm --stock box:0,0,-10,20,20,0)
(By hand, as tilted_slot.ngc: 61.9496 mm^3.)
G21 G90 G94 G17 G40 G49 G80
G0 Z60
G68.2 X0 Y0 Z0 I0 J-30 K0
G53.1
G0 X-5 Y7.660254038 Z30
G0 Z3.732050808
G1 X25 F300
G0 Z30
G69
G0 A0 C0
M30
%
