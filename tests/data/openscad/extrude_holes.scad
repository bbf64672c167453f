// A plate with two holes: polygon paths, extruded straight.
linear_extrude(height = 4)
  polygon(points = [[0, 0], [30, 0], [30, 20], [15, 26], [0, 20],
                    [5, 5], [12, 5], [12, 12], [5, 12],
                    [18, 6], [25, 6], [21.5, 14]],
          paths = [[0, 1, 2, 3, 4], [5, 6, 7, 8], [9, 10, 11]]);
