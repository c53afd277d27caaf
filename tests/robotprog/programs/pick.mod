MODULE PickModule
  ! hand-written for workcell's tests from ABB's RAPID reference
  PERS tooldata tGrip := [TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,50],[1,0,0,0],0,0,0]];
  PERS wobjdata wTable := [FALSE,TRUE,"",[[100,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];
  CONST jointtarget jHome := [[0,20,10,0,60,0],[9E9,9E9,9E9,9E9,9E9,9E9]];
  CONST robtarget pStart := [[400,-50,300],[0,0,1,0],[-1,0,0,0],[9E9,9E9,9E9,9E9,9E9,9E9]];
  VAR robtarget p;
  PROC main()
    MoveAbsJ jHome, v500, fine, tGrip;
    p := pStart;
    FOR i FROM 1 TO 3 DO
      p.trans.x := p.trans.x + 20;
      MoveL p, v200, z5, tGrip \WObj:=wTable;
    ENDFOR
    IF DInput(diPart) = 1 THEN
      MoveL pStart, v200, fine, tGrip \WObj:=wTable;
    ELSE
      MoveL Offs(p, 0, 30, 0), v200, fine, tGrip \WObj:=wTable;
    ENDIF
    SetDO doClamp, 1;
    WaitTime 0.2;
    Lift;
  ENDPROC

  PROC Lift()
    ConfJ \Off;
    MoveJ RelTool(p, 0, 0, -50), v500, fine, tGrip \WObj:=wTable;
  ENDPROC
ENDMODULE
