set terminal pngcairo size 1000,700 font ',10'
set output 'docs/bench/peers/scaling.png'
set title 'Cost per step against chain length (hanging chain, dt = 1/1920 s; ours: symplectic Euler, no stabilization; peers: their own step)'
set logscale xy
set xlabel 'links N'
set ylabel 'microseconds per step'
set key left top
set grid
plot 'docs/bench/peers/scaling.dat' index 0 using 1:2 with linespoints lw 2 pt 7 title 'dense', 'docs/bench/peers/scaling.dat' index 1 using 1:2 with linespoints lw 2 pt 7 title 'tree', 'docs/bench/peers/scaling.dat' index 2 using 1:2 with linespoints lw 2 pt 7 title 'featherstone', 'docs/bench/peers/scaling.dat' index 3 using 1:2 with linespoints lw 2 pt 7 title 'mujoco/Euler', 'docs/bench/peers/scaling.dat' index 4 using 1:2 with linespoints lw 2 pt 7 title 'mujoco/RK4', 'docs/bench/peers/scaling.dat' index 5 using 1:2 with linespoints lw 2 pt 7 title 'bullet/multibody', 'docs/bench/peers/scaling.dat' index 6 using 1:2 with linespoints lw 2 pt 7 title 'ode/worldstep', 'docs/bench/peers/scaling.dat' index 7 using 1:2 with linespoints lw 2 pt 7 title 'ode/quickstep', 'docs/bench/peers/scaling.dat' index 8 using 1:2 with linespoints lw 2 pt 7 title 'dart/ball', 2.61291*(x/8.0) with lines dt 2 lc rgb 'gray40' title 'guide: n', 2.61291*(x/8.0)**3 with lines dt 3 lc rgb 'gray20' title 'guide: n^3'
