"""The motor: parameters, the a-b model of eq. (1), its rest positions, flat maps and plant effects."""
