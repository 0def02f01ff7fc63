~VERSION INFORMATION
 VERS.                  1.2:   CWLS LOG ASCII STANDARD -VERSION 1.2
 WRAP.                  NO:   ONE LINE PER DEPTH STEP
~WELL INFORMATION BLOCK
#MNEM.UNIT       DATA TYPE    INFORMATION
#---------    -------------   ------------------------------
 STRT.M           7690.000:
 STOP.M           7683.500:
 STEP.M            -0.5000:
 NULL.           -999.2500:
 COMP.             COMPANY:   # ANY OIL COMPANY LTD.
 WELL.                WELL:   ANY ET AL OIL WELL #12
 FLD .               FIELD:   
 LOC .            LOCATION:   
 PROV.            PROVINCE:   ANY PROVINCE
 SRVC.     SERVICE COMPANY:   ANY LOGGING COMPANY LTD.
 DATE.            LOG DATE:   25-DEC-1900
 UWI .      UNIQUE WELL ID:   
~CURVE INFORMATION
#MNEM.UNIT      API CODE      CURVE DESCRIPTION
#---------    -------------   ------------------------------
 DEPT.FT                        : 
 C01.                           : 
 C02.                           : 
 C03.                           : 
 C04.                           : 
 C05.                           : 
 C06.                           : 
~P
~O
~A
    7686.000    67.354     0.140     0.415     9.207  4648.011    10.609   
    7685.500    69.004     0.151     0.412     7.020101130.188    10.560   
    7685.000    68.809     0.150     0.411     7.330-19508.961    10.424   
    7684.500    68.633     0.149     0.402     7.345116238.453    10.515   
    7684.000    68.008     0.144     0.386     7.682  4182.679    10.515   
