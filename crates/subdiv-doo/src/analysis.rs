//! Local subdivision matrices, spectra and Reif's C1 check.
