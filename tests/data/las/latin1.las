~Version
 VERS.   2.0 : CWLS log ASCII Standard - version 2.0
 WRAP.   NO  : one line per depth step
~Well
 STRT.M   10.0 : start
 STOP.M   10.2 : stop
 STEP.M    0.1 : step
 NULL.  -999.25 : null value
 WELL.   Puits Élodie-2 : well
~Curve
 DEPT.M      : profondeur
 TEMP.°C     : température
 DT  .µs/ft  : lenteur
~A
 10.0  21.5  88.1
 10.1  21.6  88.4
 10.2  21.8  -999.25
