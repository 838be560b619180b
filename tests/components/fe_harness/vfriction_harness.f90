! A stand-in for Abaqus/Explicit's side of VFRICTION (tests only): it replays the contact increments of a friction
! replay file through the routine, as the FE code calls it, in blocks of at most 136 contact points (Abaqus/Explicit's
! vector length), with the 41 arguments of the Abaqus User Subroutines Reference (node-type secondary surface: one
! state node per point, a facet main surface of 4 nodes, three dimensions, two friction directions), and keeps each
! node's states between increments as the FE code does.
!
! Replay file (text): "n_nodes n_states n_props", the properties, then per increment "dt n_points" and one line per
! contact point "node fnormal area ds1 ds2 ds3 fstick" (node 1-based). Output (stdout): per increment "F sum" (the sum of
! the friction force magnitudes -fTangential(1)), then per node "B node state(1..n_states)".
program vfriction_harness
  implicit none
  integer, parameter :: maxblk = 136, ndir = 3, nfricdir = 2, nnodmst = 4
  integer :: nnodes, nstates, nprops, ninc, i, k, n, m, ios, first
  double precision, allocatable :: states(:, :), props(:)
  integer, allocatable :: node(:)
  double precision, allocatable :: fn(:), area(:), ds(:, :), fstick(:)
  double precision :: dt, total
  character(len=512) :: path
  call get_command_argument(1, path)
  open (10, file=trim(path), status='old', action='read')
  read (10, *) nnodes, nstates, nprops
  allocate (states(nstates, nnodes), props(max(nprops, 1)))
  states = 0d0
  if (nprops > 0) read (10, *) props(1:nprops)
  ninc = 0
  do
    read (10, *, iostat=ios) dt, n
    if (ios /= 0) exit
    ninc = ninc + 1
    allocate (node(n), fn(n), area(n), ds(ndir, n), fstick(n))
    do i = 1, n
      read (10, *) node(i), fn(i), area(i), ds(1, i), ds(2, i), ds(3, i), fstick(i)
    end do
    total = 0d0
    do first = 1, n, maxblk
      m = min(maxblk, n - first + 1)
      call one_block(m, first)
    end do
    write (*, '(a, es25.17)') 'F ', total
    deallocate (node, fn, area, ds, fstick)
  end do
  do k = 1, nnodes
    write (*, '(a, i8, 8es25.17)') 'B ', k, states(:, k)
  end do
contains
  subroutine one_block(m, first)
    integer, intent(in) :: m, first
    double precision :: ftang(nfricdir, maxblk), state(nstates, 1, maxblk), rdata(4)
    double precision :: fprev(ndir, maxblk), dircosn(ndir, maxblk), dircossl(ndir, maxblk)
    double precision :: shapeslv(1, 1), shapemst(nnodmst, maxblk), coordslv(ndir, 1, maxblk)
    double precision :: coordmst(ndir, nnodmst, maxblk), velslv(ndir, 1, maxblk), velmst(ndir, nnodmst, maxblk)
    double precision :: tempslv(maxblk), tempmst(maxblk), fieldslv(1, maxblk), fieldmst(1, maxblk)
    integer :: jflags(3), jconslv(1, maxblk), jconmst(nnodmst, maxblk)
    character(len=80) :: surfint, surfslv, surfmst
    integer :: j
    ftang = 0d0; fprev = 0d0; dircosn = 0d0; dircossl = 0d0; shapeslv = 1d0; shapemst = 0.25d0
    coordslv = 0d0; coordmst = 0d0; velslv = 0d0; velmst = 0d0; tempslv = 0d0; tempmst = 0d0
    fieldslv = 0d0; fieldmst = 0d0; jflags = (/1, ninc, 1/); rdata = (/ninc * dt, ninc * dt, dt, 0d0/)
    jconmst = 0
    surfint = 'TRIBOCOSIM'; surfslv = ' '; surfmst = ' '
    do j = 1, m
      state(:, 1, j) = states(:, node(first + j - 1))
      jconslv(1, j) = node(first + j - 1)
    end do
    call vfriction(ftang, state, m, m, 1, 1, 1, nnodmst, nfricdir, ndir, nstates, nprops, 0, 1, jflags, rdata, &
                   surfint, surfslv, surfmst, jconslv, jconmst, props, ds(:, first:), fstick(first:), fprev, &
                   fn(first:), area(first:), dircosn, dircossl, shapeslv, shapemst, coordslv, coordmst, velslv, &
                   velmst, tempslv, tempmst, fieldslv, fieldmst)
    do j = 1, m
      states(:, node(first + j - 1)) = state(:, 1, j)
      total = total - ftang(1, j)
    end do
  end subroutine one_block
end program vfriction_harness

! Abaqus/Explicit's termination utility (the routine calls it after naming a refused call): exit code 3 here
subroutine xplb_exit
  stop 3
end subroutine xplb_exit
