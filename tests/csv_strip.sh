# Sourced by the sweep tests: strip FILE prints a sweep's results.csv without
# its wall-clock columns (wall_time_s, compute_time_s, time_s.*), the only
# ones that differ between two runs of one configuration. Fields are split at
# commas outside double quotes (values such as rig.units "1,2,3,4,5,6" are
# quoted); plain awk, no gawk needed.
strip() {
  awk 'function split_csv(line, f,    n, i, c, start, inq) {
         n = 0; start = 1; inq = 0
         for (i = 1; i <= length(line); i++) {
           c = substr(line, i, 1)
           if (c == "\"") inq = !inq
           else if (c == "," && !inq) { f[++n] = substr(line, start, i - start); start = i + 1 }
         }
         f[++n] = substr(line, start)
         return n
       }
       { n = split_csv($0, f)
         if (NR == 1) { columns = n; for (i = 1; i <= n; i++) keep[i] = !(f[i] == "wall_time_s" || f[i] == "compute_time_s" || f[i] ~ /^time_s\./) }
         if (n != columns) { print "row " NR " has " n " fields, the header " columns > "/dev/stderr"; exit 1 }
         out = ""; sep = ""; for (i = 1; i <= n; i++) if (keep[i]) { out = out sep f[i]; sep = "," }
         print out }' "$1"
}
