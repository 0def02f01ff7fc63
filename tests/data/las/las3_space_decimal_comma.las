~Version
 VERS.   3.0 : CWLS LOG ASCII STANDARD - VERSION 3.0
 WRAP.   NO  : one line per depth step
 DLM .   SPACE : delimiting character between data columns
~Well
 STRT.M   100.0 : first index value
 STOP.M   100.4 : last index value
 STEP.M     0.2 : step
 NULL.  -999.25 : null value
 WELL.   L3-1 : well
~Log_Parameter
 BS  .MM  215,9 : bit size {F}
~Log_Definition
 DEPT.M        : depth {F}
 PERM.mD       : permeability {F}
 LITH.         : lithology {S}
 SAMP.         : sample date {DD/MM/YYYY}
~Log_Data | Log_Definition
 100,0  12,5  "fine sand"   01/02/2020
 100,2  (null)  shale       02/02/2020
 100,4  8,25  -999.25        03/02/2020
~Core_Definition
 CORET.M : core top {F}
 CDES .  : description {S}
~Core_Data | Core_Definition
 100.0 "not read: a log is its ~Log_Data"
