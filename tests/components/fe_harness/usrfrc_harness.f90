! A caller of the LS-DYNA contact-node routine tcdynafric (tests only), as a usrfrc calls it for one node in contact.
! Reads from stdin "fnorm area ds1 ds2 ds3 dt nhsv hsv(1..nhsv) nuc uc(1..nuc)" and prints
! "fric(1..4) hsv(1..nhsv)".
program usrfrc_harness
  implicit none
  integer :: nhsv, nuc
  double precision :: fnorm, area, ds(3), dt, fric(4)
  double precision, allocatable :: hsv(:), uc(:)
  read (*, *) fnorm, area, ds(1), ds(2), ds(3), dt, nhsv
  allocate (hsv(max(nhsv, 1)))
  read (*, *) hsv(1:nhsv), nuc
  allocate (uc(max(nuc, 1)))
  if (nuc > 0) read (*, *) uc(1:nuc)
  call tcdynafric(fnorm, area, ds, 3, dt, hsv, nhsv, uc, nuc, fric)
  write (*, '(20es25.17)') fric, hsv(1:nhsv)
end program usrfrc_harness
