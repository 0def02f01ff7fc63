~Version
 VERS.   2.0 : CWLS log ASCII Standard - version 2.0
 WRAP.   NO  : one line per time step
~Well
 STRT.S   0.0 : start
 STOP.S   2.0 : stop
 STEP.S   1.0 : step
 NULL.  -999.25 : null value
 WELL.   T-3 : well
~Curve
 ETIM.S       : elapsed time
 CLOCK.HHMMSS : time of day
 HKLD.KLB     : hook load
 SPP .PSI     : standpipe pressure
~A
 0.0  23:59:58  181.2  NaN
 1.0  23:59:59  -1.#IND  2450.0
 2.0  00:00:00  182.0  (null)
