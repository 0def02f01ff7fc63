~VERSION INFORMATION
VERS.                          2.0 :   CWLS LOG ASCII STANDARD -VERSION 2.0
WRAP.                          NO  :   ONE LINE PER DEPTH STEP
~WELL INFORMATION 
#MNEM.UNIT              DATA                       DESCRIPTION
#----- -----            ----------               -------------------------
STRT    .F              19160                    :START DEPTH
STOP    .F              19160.5                  :STOP DEPTH
STEP    .F                  0.5                  :STEP 
NULL    .                -999.25                 :NULL VALUE
COMP    .       ANY OIL COMPANY INC.             :COMPANY
WELL    .       AAAAA_2            :WELL
FLD     .       WILDCAT                          :FIELD
LOC     .       12-34-12-34W5M                   :LOCATION
PROV    .       ALBERTA                          :PROVINCE 
SRVC    .       ANY LOGGING COMPANY INC.         :SERVICE COMPANY
DATE    .       13-DEC-86                        :LOG DATE
UWI     .       100123401234W500                 :UNIQUE WELL ID
 ~Curve Information
 DEPTH.F                : 1    DEPTH
 TVD.F                  : 2    TVD
 VS.F                   : 3    VS
 Gamma.CPM              : 6    Gamma
 ROP.Ft/Hr              : 5    ROP
 TEMP.F                 : 6    Temperature (Tool)
~A DEPTH         TVD          VS     Gamma
 19160.0   10415.184    8974.944    57.011
 19160.5   10415.190    8975.444    57.011
