"""The velocity discretisation: the periodic grid, quadratures on the radius, circle and
sphere, the heat-bath multiplier and a-posteriori resolution indicators."""
