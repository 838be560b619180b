! A stand-in for Abaqus/Standard's side of FRIC (tests only): one call at one contact point of a three-dimensional
! contact pair (two friction directions), with the 39 arguments of the Abaqus User Subroutines Reference. Reads from
! stdin "lm press dgam1 dgam2 dtime chrlngth tau1 tau2 nstatv statev(1..nstatv) nprops props(1..nprops)" and prints
! "lm tau1 tau2 ddtddg(1,1) ddtddg(2,1) ddtddg(1,2) ddtddg(2,2) ddtddp1 ddtddp2 statev(1..nstatv)".
program fric_harness
  implicit none
  integer, parameter :: nfdir = 2, mcrd = 3, npred = 1
  integer :: lm, nstatv, nprops, kstep, kinc, noel, npt, node, npatch
  double precision :: tau(nfdir), ddtddg(nfdir, nfdir), ddtddp(nfdir), dslip(nfdir), ddtddt(nfdir, 2), dgam(nfdir)
  double precision :: taulm(nfdir), slip(nfdir), time(2), coords(mcrd), rcoord(mcrd), drot(2, 2), temp(2)
  double precision :: predef(2, npred), sed, sfd, pnewdt, press, dpress, ddpddh, dtime, chrlngth
  double precision, allocatable :: statev(:), props(:)
  character(len=80) :: ciname, slname, msname
  read (*, *) lm, press, dgam(1), dgam(2), dtime, chrlngth, tau(1), tau(2), nstatv
  allocate (statev(max(nstatv, 1)))
  read (*, *) statev(1:nstatv), nprops
  allocate (props(max(nprops, 1)))
  if (nprops > 0) read (*, *) props(1:nprops)
  ddtddg = 0d0; ddtddp = 0d0; dslip = 0d0; ddtddt = 0d0; taulm = 0d0; slip = 0d0; time = (/1d0, 1d0/)
  coords = 0d0; rcoord = 0d0; drot = 0d0; temp = 0d0; predef = 0d0; sed = 0d0; sfd = 0d0; pnewdt = 1d0
  dpress = 0d0; ddpddh = 0d0; kstep = 1; kinc = 1; noel = 1; npt = 1; node = 1; npatch = 1
  ciname = 'TRIBOCOSIM'; slname = 'SHEET'; msname = 'TOOL'
  call fric(lm, tau, ddtddg, ddtddp, dslip, sed, sfd, ddtddt, pnewdt, statev, dgam, taulm, press, dpress, ddpddh, &
            slip, kstep, kinc, time, dtime, noel, ciname, slname, msname, npt, node, npatch, coords, rcoord, drot, &
            temp, predef, nfdir, mcrd, npred, nstatv, chrlngth, props, nprops)
  write (*, '(i3, 20es25.17)') lm, tau, ddtddg, ddtddp, statev(1:nstatv)
end program fric_harness

! Abaqus/Standard's termination utility (the routine calls it after naming a refused call): exit code 3 here
subroutine xit
  stop 3
end subroutine xit
