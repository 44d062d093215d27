set terminal pngcairo size 1000,700 font ',10'
set output 'docs/bench/scaling.png'
set title 'Cost per step against chain length (symplectic Euler, no stabilization, hanging chain, dt = 1/1920 s)'
set logscale xy
set xlabel 'links N'
set ylabel 'microseconds per step'
set key left top
set grid
plot 'docs/bench/scaling.dat' index 0 using 1:2 with linespoints lw 2 pt 7 title 'dense', 'docs/bench/scaling.dat' index 1 using 1:2 with linespoints lw 2 pt 7 title 'tree', 'docs/bench/scaling.dat' index 2 using 1:2 with linespoints lw 2 pt 7 title 'featherstone', 2.1526*(x/2.0) with lines dt 2 lc rgb 'gray40' title 'guide: n', 2.1526*(x/2.0)**3 with lines dt 3 lc rgb 'gray20' title 'guide: n^3'
