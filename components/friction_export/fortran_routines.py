"""The Fortran text of the user friction routines: Abaqus/Explicit VFRICTION, Abaqus/Standard FRIC and the LS-DYNA
contact-node routine, each a thin shim that passes the FE code's arguments to the C functions of
``components/native/fe/tc_fe_friction.c`` through a ``bind(C)`` interface (Fortran 2003: the C names and types are the
standard's, whatever the compiler's own naming; the types are checked against the interface at compile time, so a
single-precision Abaqus/Explicit build, whose reals are not ``c_double``, does not compile).

Argument lists (Fortran binds by position; the names are the references'):

- VFRICTION: Abaqus User Subroutines Reference, "VFRICTION" (Abaqus/Explicit, general contact): 41 arguments
  fTangential, state, nBlock, nBlockAnal, nBlockEdge, nNodState, nNodSlv, nNodMst, nFricDir, nDir, nStates, nProps,
  nTemp, nFields, jFlags, rData, surfInt, surfSlv, surfMst, jConSlvUid, jConMstUid, props, dSlipFric, fStickForce,
  fTangPrev, fNormal, areaCont, dircosN, dircosSl, shapeSlv, shapeMst, coordSlv, coordMst, velSlv, velMst, tempSlv,
  tempMst, fieldSlv, fieldMst, with the array sizes of its template (the order as in the public VFRICTION of the WZL
  friction model, JStaWZL/USR_VFriction_WZLReibmodell, made with Abaqus 6.14); rData(3) is the time increment.
- FRIC: Abaqus User Subroutines Reference, "FRIC" (Abaqus/Standard): 39 arguments LM, TAU, DDTDDG, DDTDDP, DSLIP,
  SED, SFD, DDTDDT, PNEWDT, STATEV, DGAM, TAULM, PRESS, DPRESS, DDPDDH, SLIP, KSTEP, KINC, TIME, DTIME, NOEL, CINAME,
  SLNAME, MSNAME, NPT, NODE, NPATCH, COORDS, RCOORD, DROT, TEMP, PREDEF, NFDIR, MCRD, NPRED, NSTATV, CHRLNGTH, PROPS,
  NPROPS (the 2016-2017 editions, whose template includes ``ABA_PARAM.INC``; the file includes ``aba_param.inc``, the
  name of the file in an Abaqus installation on a case-sensitive file system).
- LS-DYNA: the argument list of LS-DYNA's user friction subroutine (``usrfrc`` of the user object's ``dyn21`` files,
  LS-DYNA Keyword User's Manual, *USER_INTERFACE_FRICTION and its appendix on user defined interface friction) could
  not be verified from a public source here: the file holds a routine of its own, ``tcdynafric``, with a documented
  argument list that a ``usrfrc`` calls for each contact node, and names what must be checked against the manual.

Fixed form, as Abaqus's own templates: statements in columns 7-72, continuation in column 6, comments from ``C`` in
column 1; double precision throughout (``vaba_param.inc`` / ``aba_param.inc`` give ``implicit real*8 (a-h,o-z)`` in a
double-precision run).
"""

from __future__ import annotations

import textwrap

#: what a status of the C functions means (enum tc_fe_status of tc_fe_friction.h)
STATUS = {1: "fewer than 2 state variables per point (DEPVAR: state 1 beta, state 2 the accumulated slip)",
          2: "property 1 is not the check number of this export",
          3: "an array size of the call the routine cannot take"}


def comment(lines, width: int = 69) -> str:
    """Fortran comment lines (``C`` in column 1), wrapped to ``width``."""
    out = []
    for line in lines:
        wrapped = textwrap.wrap(line, width, subsequent_indent="    ", break_long_words=True,
                                break_on_hyphens=False) or [""]
        out += [f"C {w}".rstrip() for w in wrapped]
    return "\n".join(out)


def _stop(routine: str, stopper: str, check: int) -> str:
    """The subroutine that names a refused call's status and stops the analysis."""
    name = {"VFRICTION": "tcvfrstop", "FRIC": "tcfrstop", "LS-DYNA": "tcdystop"}[routine]
    cases = []
    for code, what in STATUS.items():
        text = what if code != 2 else f"{what} ({check}, PROPERTIES=1)"
        pieces = textwrap.wrap(f"tribocosim {routine}: {text}", 40)
        lit = "\n".join([f"        write(*,'(a)') '{pieces[0]}'"] +
                        [f"        write(*,'(a)') '  {p}'" for p in pieces[1:]])
        cases.append(f"      if (kstat .eq. {code}) then\n{lit}\n      end if")
    return (f"      subroutine {name}(kstat)\n"
            "C the status of a refused call, in words, then the analysis stops\n"
            "      integer kstat\n" + "\n".join(cases) + "\n"
            f"      call {stopper}\n"
            "      return\n"
            "      end\n")


def vfriction(header: list[str], check: int) -> str:
    """The VFRICTION file (Abaqus/Explicit)."""
    return comment(header) + """
C
      subroutine vfriction (
C Write only -
     *   fTangential,
C Read/Write -
     *   state,
C Read only -
     *   nBlock, nBlockAnal, nBlockEdge,
     *   nNodState, nNodSlv, nNodMst,
     *   nFricDir, nDir,
     *   nStates, nProps, nTemp, nFields,
     *   jFlags, rData,
     *   surfInt, surfSlv, surfMst,
     *   jConSlvUid, jConMstUid, props,
     *   dSlipFric, fStickForce, fTangPrev, fNormal,
     *   areaCont, dircosN, dircosSl,
     *   shapeSlv, shapeMst,
     *   coordSlv, coordMst,
     *   velSlv, velMst,
     *   tempSlv, tempMst,
     *   fieldSlv, fieldMst )
C
      include 'vaba_param.inc'
C
      dimension fTangential(nFricDir,nBlock),
     *   state(nStates,nNodState,nBlock),
     *   jConSlvUid(nNodSlv,nBlock),
     *   jConMstUid(nNodMst,nBlockAnal),
     *   props(nProps),
     *   dSlipFric(nDir,nBlock),
     *   fStickForce(nBlock),
     *   fTangPrev(nDir,nBlock),
     *   fNormal(nBlock),
     *   areaCont(nBlock),
     *   dircosN(nDir,nBlock),
     *   dircosSl(nDir,nBlock),
     *   shapeSlv(nNodSlv,nBlockEdge),
     *   shapeMst(nNodMst,nBlockAnal),
     *   coordSlv(nDir,nNodSlv,nBlock),
     *   coordMst(nDir,nNodMst,nBlockAnal),
     *   velSlv(nDir,nNodSlv,nBlock),
     *   velMst(nDir,nNodMst,nBlockAnal),
     *   tempSlv(nBlock),
     *   tempMst(nBlockAnal),
     *   fieldSlv(nFields,nBlock),
     *   fieldMst(nFields,nBlockAnal)
C
      parameter( iKStep    = 1,
     *           iKInc     = 2,
     *           iLConType = 3,
     *           nFlags    = 3 )
      parameter( iTimStep      = 1,
     *           iTimGlb       = 2,
     *           iDTimCur      = 3,
     *           iFrictionWork = 4,
     *           nData         = 4 )
      dimension jFlags(nFlags), rData(nData)
      character*80 surfInt, surfSlv, surfMst
C
      interface
        subroutine tcvfr(nblk, ndr, nfdr, nst, nnst, prp, nprp, dt,
     *      ds, fst, fn, ar, st, ft, kst)
     *      bind(c, name='tribocosim_vfriction')
          use, intrinsic :: iso_c_binding, only: c_int, c_double
          implicit none
          integer(c_int), value :: nblk, ndr, nfdr, nst, nnst, nprp
          real(c_double), value :: dt
          real(c_double), intent(in) :: prp(*), ds(*), fst(*), fn(*)
          real(c_double), intent(in) :: ar(*)
          real(c_double), intent(inout) :: st(*)
          real(c_double), intent(out) :: ft(*)
          integer(c_int), intent(out) :: kst
        end subroutine tcvfr
      end interface
C
C every contact point of the block through tribocosim's C core
      call tcvfr(nBlock, nDir, nFricDir, nStates, nNodState, props,
     *   nProps, rData(iDTimCur), dSlipFric, fStickForce, fNormal,
     *   areaCont, state, fTangential, kstat)
      if (kstat .ne. 0) call tcvfrstop(kstat)
C
      return
      end
C
""" + _stop("VFRICTION", "xplb_exit", check)


def fric(header: list[str], check: int) -> str:
    """The FRIC file (Abaqus/Standard)."""
    return comment(header) + """
C
      SUBROUTINE FRIC(LM,TAU,DDTDDG,DDTDDP,DSLIP,SED,SFD,
     1 DDTDDT,PNEWDT,STATEV,DGAM,TAULM,PRESS,DPRESS,DDPDDH,SLIP,
     2 KSTEP,KINC,TIME,DTIME,NOEL,CINAME,SLNAME,MSNAME,NPT,NODE,
     3 NPATCH,COORDS,RCOORD,DROT,TEMP,PREDEF,NFDIR,MCRD,NPRED,
     4 NSTATV,CHRLNGTH,PROPS,NPROPS)
C
      INCLUDE 'aba_param.inc'
C
      CHARACTER*80 CINAME,SLNAME,MSNAME
C
      DIMENSION TAU(NFDIR),DDTDDG(NFDIR,NFDIR),DDTDDP(NFDIR),
     1 DSLIP(NFDIR),DDTDDT(NFDIR,2),STATEV(*),DGAM(NFDIR),
     2 TAULM(NFDIR),SLIP(NFDIR),TIME(2),COORDS(MCRD),
     3 RCOORD(MCRD),DROT(2,2),TEMP(2),PREDEF(2,*),PROPS(NPROPS)
C
      INTERFACE
        SUBROUTINE TCFRC(LMF, TF, DG, DP, DGM, PR, DT, CL, NFD, SV,
     *      NSV, PRP, NPRP, KST)
     *      BIND(C, NAME='tribocosim_fric')
          USE, INTRINSIC :: ISO_C_BINDING, ONLY: C_INT, C_DOUBLE
          IMPLICIT NONE
          INTEGER(C_INT), INTENT(INOUT) :: LMF
          INTEGER(C_INT), VALUE :: NFD, NSV, NPRP
          REAL(C_DOUBLE), VALUE :: PR, DT, CL
          REAL(C_DOUBLE), INTENT(INOUT) :: TF(*), SV(*)
          REAL(C_DOUBLE), INTENT(OUT) :: DG(*), DP(*)
          REAL(C_DOUBLE), INTENT(IN) :: DGM(*), PRP(*)
          INTEGER(C_INT), INTENT(OUT) :: KST
        END SUBROUTINE TCFRC
      END INTERFACE
C
C the contact point through tribocosim's C core
      CALL TCFRC(LM, TAU, DDTDDG, DDTDDP, DGAM, PRESS, DTIME,
     *   CHRLNGTH, NFDIR, STATEV, NSTATV, PROPS, NPROPS, KSTAT)
      IF (KSTAT .NE. 0) CALL TCFRSTOP(KSTAT)
C
      RETURN
      END
C
""" + _stop("FRIC", "xit", check)


def lsdyna(header: list[str], check: int) -> str:
    """The LS-DYNA file: the contact-node routine and, as comments, where a usrfrc calls it."""
    return comment(header) + """
C
      subroutine tcdynafric(fnorm, area, dslip, ndir, dt, hsv, nhsv,
     *   uc, nuc, fric)
C
C One LS-DYNA contact node in contact: fnorm the normal force at the
C node, area its contact area, dslip(ndir) its slip increment of the
C cycle, dt the time step, hsv(nhsv) its history variables (the
C states of the header), uc(nuc) the interface's user constants
C (uc(1): the check number). Returns fric(1..4) = static and dynamic
C coefficient, decay and viscous coefficient: (mu, mu, 0, 0).
C
      implicit double precision (a-h,o-z)
      dimension dslip(ndir), hsv(nhsv), uc(nuc), fric(4)
C
      interface
        subroutine tcdyn(fn, ar, ds, nd, dt, hv, nhv, u, nu, fr, kst)
     *      bind(c, name='tribocosim_usrfrc')
          use, intrinsic :: iso_c_binding, only: c_int, c_double
          implicit none
          real(c_double), value :: fn, ar, dt
          integer(c_int), value :: nd, nhv, nu
          real(c_double), intent(in) :: ds(*), u(*)
          real(c_double), intent(inout) :: hv(*)
          real(c_double), intent(out) :: fr(*)
          integer(c_int), intent(out) :: kst
        end subroutine tcdyn
      end interface
C
      call tcdyn(fnorm, area, dslip, ndir, dt, hsv, nhsv, uc, nuc,
     *   fric, kstat)
      if (kstat .ne. 0) call tcdystop(kstat)
      return
      end
C
""" + _stop("LS-DYNA", "adios", check).replace("      call adios\n", "      stop 2\n")
