~Version Information Block
 VERS.                2.00:     CWLS LOG ASCII STANDARD - VERSION 2.000000
 WRAP.                  NO:     One Line Per Depth Step
#
~Well Information Block
#MNEM.UNIT                     Data                         Information
#----------   ------------------------------------------   ----------------
 STRT.FT                                     2450.0000:     START DEPTH
 STOP.FT                                     2550.0000:     STOP DEPTH
 STEP.FT                                        0.5000:     STEP LENGTH
 NULL.                                       -999.2500:     NULL VALUE
 COMP.                      Drillers & Producers, Inc.:     COMPANY
 LEAS.                                           Berry:     LEASE NAME
 WELL.                                               2:     WELL NUM
~Curve Information Block
 DEPT.FT                   :   Depth in Feet
 GR  .GAPI                 :   Gamma Ray
 CN  .PU                   :   Compensated Neutron
 CD  .PU                   :   Compensated Density
~A DEPTH     GR               CN               CD              
    2450.000 141.53386454     -1.#IND0000      -1.#IND0000     
    2450.500 141.53386454     -1.#IND0000      -1.#IND0000     
    2451.000 140.92327541     -1.#IND0000      -1.#IND0000     
    2451.500 138.84323879     -1.#IND0000      -1.#IND0000     
    2452.000 135.69677278     -1.#IND0000      -1.#IND0000     
    2452.500 132.29497308     -1.#IND0000      -1.#IND0000     
    2453.000 131.95062005     -1.#IND0000      -1.#IND0000     
    2453.500 134.61177433     -1.#IND0000      -1.#IND0000     
    2454.000 135.16463889     -1.#IND0000      -1.#IND0000     
    2454.500 131.08716622     -1.#IND0000      -1.#IND0000     