/PROG  PICK
/ATTR
OWNER		= MNEDITOR;
COMMENT		= "hand-written";
PROG_SIZE	= 0;
CREATE		= DATE 24-01-01  TIME 00:00:00;
MODIFIED	= DATE 24-01-01  TIME 00:00:00;
FILE_NAME	= ;
VERSION		= 0;
LINE_COUNT	= 21;
MEMORY_SIZE	= 0;
PROTECT		= READ_WRITE;
TCD:  STACK_SIZE	= 0,
      TASK_PRIORITY	= 50,
      TIME_SLICE	= 0,
      BUSY_LAMP_OFF	= 0,
      ABORT_REQUEST	= 0,
      PAUSE_REQUEST	= 0;
DEFAULT_GROUP	= 1,*,*,*,*;
CONTROL_CODE	= 00000000 00000000;
/MN
   1:  ! hand-written for workcell tests ;
   2:  UFRAME_NUM=0 ;
   3:  PR[1,3]=100 ;
   4:  UTOOL[1]=PR[1] ;
   5:  UTOOL_NUM=1 ;
   6:  J P[1] 50% FINE ;
   7:  PR[2]=P[2] ;
   8:  FOR R[1]=1 TO 3 ;
   9:    PR[2,1]=PR[2,1]+20 ;
  10:    L PR[2] 250mm/sec CNT5 ;
  11:  ENDFOR ;
  12:  PR[3,2]=30 ;
  13:  IF DI[1]=ON,JMP LBL[1] ;
  14:  L PR[2] 200mm/sec FINE Offset,PR[3] ;
  15:  LBL[1] ;
  16:  DO[2:clamp]=ON ;
  17:  WAIT   0.20(sec) ;
  18:  C P[3]
    :    P[4] 100mm/sec FINE ;
  19:  // L P[4] 100mm/sec FINE ;
/POS
P[1]{
   GP1:
	UF : 0, UT : 1,	
	J1=     0.000 deg,	J2=    10.000 deg,	J3=   -10.000 deg,
	J4=     0.000 deg,	J5=   -80.000 deg,	J6=     0.000 deg
};
P[2]{
   GP1:
	UF : 0, UT : 1,		CONFIG : 'N U T, 0, 0, 0',
	X =   400.000  mm,	Y =   -50.000  mm,	Z =   350.000  mm,
	W =   180.000 deg,	P =     0.000 deg,	R =     0.000 deg
};
P[3:"arc via"]{
   GP1:
	UF : 0, UT : 1,		CONFIG : 'N U T, 0, 0, 0',
	X =   480.000  mm,	Y =     0.000  mm,	Z =   350.000  mm,
	W =   180.000 deg,	P =     0.000 deg,	R =     0.000 deg
};
P[4]{
   GP1:
	UF : 0, UT : 1,		CONFIG : 'N U T, 0, 0, 0',
	X =   460.000  mm,	Y =    20.000  mm,	Z =   350.000  mm,
	W =   180.000 deg,	P =     0.000 deg,	R =     0.000 deg
};
/END
