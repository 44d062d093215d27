set terminal pngcairo size 1000,700 font ',10'
set output 'docs/bench/scaling.png'
set title 'Cost per step against chain length (hanging chain, dt = 1/1920 s; ours: symplectic Euler, no stabilization; peers: their own step)'
set logscale xy
set xlabel 'links N'
set ylabel 'microseconds per step'
set key left top
set grid
plot 'docs/bench/scaling.dat' index 0 using 1:2 with linespoints lc rgb '#1f77b4' lw 3 pt 7 title 'dense', 'docs/bench/scaling.dat' index 1 using 1:2 with linespoints lc rgb '#ff7f0e' lw 3 pt 7 title 'tree', 'docs/bench/scaling.dat' index 2 using 1:2 with linespoints lc rgb '#2ca02c' lw 3 pt 7 title 'featherstone', 'docs/bench/scaling.dat' index 3 using 1:2 with linespoints lc rgb '#d62728' lw 1.5 dt 2 pt 7 title 'mujoco/Euler', 'docs/bench/scaling.dat' index 4 using 1:2 with linespoints lc rgb '#9467bd' lw 1.5 dt 2 pt 8 title 'mujoco/RK4', 'docs/bench/scaling.dat' index 5 using 1:2 with linespoints lc rgb '#8c564b' lw 1.5 dt 2 pt 9 title 'bullet/multibody', 'docs/bench/scaling.dat' index 6 using 1:2 with linespoints lc rgb '#e377c2' lw 1.5 dt 2 pt 10 title 'ode/worldstep', 'docs/bench/scaling.dat' index 7 using 1:2 with linespoints lc rgb '#17becf' lw 1.5 dt 2 pt 11 title 'ode/quickstep', 'docs/bench/scaling.dat' index 8 using 1:2 with linespoints lc rgb '#bcbd22' lw 1.5 dt 2 pt 4 title 'dart/ball', 0.348778*(x/2.0) with lines dt 2 lc rgb 'gray40' title 'guide: n', 0.348778*(x/2.0)**3 with lines dt 3 lc rgb 'gray20' title 'guide: n^3'
