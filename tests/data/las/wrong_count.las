~Version Information
 VERS.   2.0 : CWLS log ASCII Standard - version 2.0
 WRAP.   NO  : one line per depth step
~Well Information
 STRT.M        1500.0 : start depth
 STOP.M        1502.0 : stop depth
 STEP.M           0.5 : step
 NULL.        -999.25 : null value
 COMP.   Example Oil Co. : company
 WELL.   GR-7            : well
 FLD .   North Field     : field
 UWI .   100/07-12-045-06W5/00 : unique well identifier
 LATI.DEG     52.8771 : latitude
 LONG.DEG   -114.8245 : longitude
 DATE.   2021-03-14      : log date
~Curve Information
 DEPT.M       : measured depth
 GR  .GAPI    : gamma ray
 RHOB.G/CC    : bulk density
 NPHI.V/V     : neutron porosity
~Parameter Information
 BS  .MM  215.9 : bit size
~A  DEPT      GR     RHOB    NPHI
 1500.0    45.20   2.410   0.210
 1500.5  -999.25   2.430   0.220
 1501.0    52.90   2.450
 1501.5    61.00 -999.25   0.185
 1502.0    58.40   2.470   0.200
