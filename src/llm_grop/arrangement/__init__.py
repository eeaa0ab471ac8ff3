"""Paper §III-A and §III-B: symbolic relations, consistency, geometry, sampling."""
