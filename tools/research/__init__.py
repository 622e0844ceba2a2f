"""Research kernels kept as independent references for the tests (not shipped in the extension): a glow over
lit parts of a segment (Biri 2006), the APSF series (Narasimhan and Nayar 2003), the phase function's Legendre
series (Sun et al. 2005 App. D)."""
