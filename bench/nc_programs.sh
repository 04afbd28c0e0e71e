#!/bin/sh
# The generated three-axis programs of the post benchmarks (bench/post_vs_rs274.sh,
# the callgrind figures of README and docs/post.md "Speed").
# Usage: bench/nc_programs.sh raster|circle N [WRAP] > program.ngc
#   raster: issue #5's raster (28 bytes a line): 401 moves a pass along X at
#           0.5 mm, Y stepping 0.1 mm, Z a smooth surface; Y back to 0 past
#           WRAP mm (0: never). Lines of X Y Z words alone, every word of
#           which the sample's errors change: the post writes each line anew.
#   circle: issue #35's every-line-changes program (24 bytes a line): a circle
#           of radius 100 mm round the program origin at Z-2, in G1 moves
#           0.314 mm long written as CAM posts that repeat the motion write
#           them ("G1 X.. Y.. Z-2"; 2 000.5 moves a turn, so that no two turns
#           pass through the same points). With the sample's errors and
#           --work-offset 250,200,100 (the circle in the middle of the
#           500 x 400 mm travel) every line's correction changes: the post
#           changes every line, each word renumbered in place.
gen_raster() {  # N [WRAP]
  awk -v N="$1" -v W="${2:-0}" 'BEGIN{print "%";print "G21 G90 G17 G40 G49 G80";print "G0 Z10";print "G0 X0 Y0";print "G1 Z-2 F2000";n=0;y=0;dir=1;while(n<N){for(i=0;i<=400&&n<N;i++){x=dir>0?i*0.5:200-i*0.5;z=-5+3*sin(x/20)*cos(y/15);printf "X%.4f Y%.4f Z%.4f\n",x,y,z;n++}y+=0.1;if(W>0&&y>W)y=0;dir=-dir}print "G0 Z10";print "M2";print "%"}'
}
gen_circle() {  # N
  awk -v N="$1" 'BEGIN{
    pi = atan2(0, -1); r = 100; step = 2 * pi / 2000.5
    print "%"; print "G21 G90 G17 G40 G49 G80"; print "G0 Z10"
    printf "G0 X%.4f Y%.4f\n", r, 0; print "G1 Z-2 F2000"
    for (n = 1; n <= N; n++) printf "G1 X%.4f Y%.4f Z-2\n", r * cos(n * step), r * sin(n * step)
    print "G0 Z10"; print "M2"; print "%"}'
}
case ${1:-} in
raster) gen_raster "${2:?N}" "${3:-0}" ;;
circle) gen_circle "${2:?N}" ;;
*) echo "usage: $0 raster|circle N [WRAP]" >&2; exit 2 ;;
esac
