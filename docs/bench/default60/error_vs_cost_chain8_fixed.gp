set terminal pngcairo size 1400,900 font ',10'
set output 'docs/bench/default60/error_vs_cost_chain8_fixed.png'
set title "chain N=8 fixed: RMS error over the converged horizon against cost (one point per dt)"
set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set xlabel 'cost: wall seconds per simulated second'
set ylabel 'RMS error of the tracked point (m)'
set key outside right top font ',9' spacing 1.2
set grid
plot 'docs/bench/default60/error_vs_cost_chain8_fixed.dat' index 0 using 1:2 with linespoints lw 2.5 dt 1 pt 5 ps 1.6 lc rgb '#2ca02c' notitle, 'docs/bench/default60/error_vs_cost_chain8_fixed.dat' index 1 using 1:2 with linespoints lw 2.5 dt 1 pt 13 ps 1 lc rgb '#d62728' notitle, NaN with lines lw 4 lc rgb '#2ca02c' title "integrator rattle", NaN with lines lw 4 lc rgb '#d62728' title "integrator RK4", NaN with points pt 5 ps 1.5 lc rgb 'black' title "solver tree", NaN with points pt 13 ps 1.5 lc rgb 'black' title "solver mujoco", NaN with lines lw 1.5 dt 1 lc rgb 'black' title "stabilization none", NaN with linespoints lw 2.5 pt 6 ps 1.6 lc rgb 'gray30' title "thick, large: step control (+auto, +tol)", 'docs/bench/default60/error_vs_cost_chain8_fixed.dat' index 2 using 1:2 with steps lw 3 lc rgb 'black' dt 2 title 'Pareto front', 'docs/bench/default60/error_vs_cost_chain8_fixed.dat' index 2 using 1:2 with points pt 6 ps 2.2 lw 2 lc rgb 'black' notitle
