%
O0001 (written for trochomill's tests: calls O5000, the serial-number macro, as its README says)
G20 G17 G40 G80 G90
T1 M6
G54 G0 X0 Y0 S8000 M3
G43 H1 Z1.
G65 P5000 A1234. F10. R0.1 X0.5 Y0.5 Z-0.005
G0 Z1.
M30
%
